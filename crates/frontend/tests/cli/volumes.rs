//! Volumetric billboards from the command line: `pipeline check` names the slicing knob out
//! of range, `render assets/scenes/volumetric.ron` draws the translucent volumes over the
//! opaque frame, and a scene with a bad volume is refused naming its field.

use super::{pass_names, ssbvb, stdout_json};

const VOLUMETRIC: &str = include_str!("../../../../assets/pipelines/volumetric.ron");

#[test]
fn pipeline_check_rejects_each_slicing_knob_out_of_range_by_name() {
    let from = "VolumeSlices(slice_spacing: 0.5, mip_bias: 0.0)";
    let edits: Vec<(String, &str)> = [
        ("slice_spacing: 0.0", "slice_spacing"),
        ("slice_spacing: 9.0", "slice_spacing"),
        ("slice_spacing: 0.5, mip_bias: 11.0", "mip_bias"),
    ]
    .into_iter()
    .map(|(to, knob)| (format!("VolumeSlices({to})"), knob))
    .collect();
    let edits: Vec<(&str, &str, &str)> = edits
        .iter()
        .map(|(to, knob)| (from, to.as_str(), *knob))
        .collect();
    super::assert_knobs_refused(VOLUMETRIC, "volumes", "VolumeSlices", &edits);
}

#[test]
fn the_volumetric_scene_renders_and_bad_volumes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let render = |scene: &std::path::Path, name: &str| {
        let png = dir.path().join(name);
        let out = ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .args(["render", "--size", "128x96", "--json"])
            .arg(scene)
            .arg("-o")
            .arg(&png)
            .output()
            .unwrap();
        (out, png)
    };
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes");
    let (out, png) = render(&scenes.join("volumetric.ron"), "volumes.png");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = stdout_json(&out);
    let passes = pass_names(&json);
    assert!(passes.iter().any(|p| p == "volumes"), "{passes:?}");
    // The same scene without its volumes: the cloud and the translucent bunny change
    // pixels, and some of the sky behind the opaque frame (alpha 0 there) gains alpha.
    let text = std::fs::read_to_string(scenes.join("volumetric.ron")).unwrap();
    let start = text.find("  volumes: [").unwrap();
    let end = text[start..].find("\n  ],\n").unwrap() + start + "\n  ],\n".len();
    let bare = dir.path().join("bare.ron");
    let abs = |p: &str| scenes.join(p).display().to_string();
    let bare_text = text[..start].to_string() + &text[end..];
    let bare_text = bare_text
        .replace("../pipelines/", &abs("../pipelines/"))
        .replace("../models/", &abs("../models/"));
    std::fs::write(&bare, bare_text).unwrap();
    let (out, bare_png) = render(&bare, "bare.png");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (a, b) = (
        image::open(&png).unwrap().to_rgba8(),
        image::open(&bare_png).unwrap().to_rgba8(),
    );
    let changed = a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count();
    let sky = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| q[3] == 0 && p[3] > 0)
        .count();
    assert!(changed > 500 && sky > 100, "changed {changed}, sky {sky}");
    // A bad volume: the scene file, the entry and the field are named.
    let bad = dir.path().join("bad.ron");
    std::fs::write(
        &bad,
        "Scene(volumes: [(source: Cloud(density: -2.0), edge: 64)])",
    )
    .unwrap();
    let (out, _) = render(&bad, "bad.png");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("bad.ron") && err.contains("volumes[0].source: Cloud density"),
        "{err}"
    );
}
