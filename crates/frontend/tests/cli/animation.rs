//! Animated scene objects: `animate:` in a scene file and `ssbvb render SCENE --time T`.

use std::path::Path;

use super::{ssbvb, stdout_json, succeeded};

fn render(scene: &Path, time: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    ssbvb()
        .arg("render")
        .arg(scene)
        .args(["--size", "96x72", "--time", time, "--json", "-o"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn an_animated_scene_renders_at_the_time_asked_and_reports_its_update() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = tempfile::tempdir().unwrap();
    // The bundled twisting bunny, at level 5 to stay quick.
    let text = std::fs::read_to_string(root.join("assets/scenes/twisting_bunny.ron"))
        .unwrap()
        .replace("level: 7", "level: 5")
        .replace("\"../", &format!("\"{}/assets/", root.display()));
    let scene = dir.path().join("twist.ron");
    std::fs::write(&scene, &text).unwrap();
    let mut images = Vec::new();
    for t in ["0", "1.0"] {
        let png = dir.path().join(format!("t{t}.png"));
        let out = render(&scene, t, &png, &[]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json = stdout_json(&out);
        let a = &json["animation"];
        assert_eq!(a["time_s"].as_f64(), Some(t.parse().unwrap()), "{a}");
        let o = &a["objects"][0];
        for key in ["deform_ms", "voxelize_ms", "lod_ms", "copy_ms", "total_ms"] {
            assert!(o[key].as_f64().unwrap() >= 0.0, "{key}: {o}");
        }
        assert!(o["voxels"].as_u64().unwrap() > 500, "{o}");
        images.push(image::open(&png).unwrap().to_rgba8());
    }
    let differ = images[0]
        .pixels()
        .zip(images[1].pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        differ > 200,
        "the twist changes the picture: {differ} pixels"
    );
    // The reference at the same time, posed on the CPU.
    let out = render(&scene, "1.0", &dir.path().join("ref.png"), &["--reference"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = stdout_json(&out);
    assert_eq!(json["animation"]["method"], serde_json::Value::Null);
    // Bad input: a voxel model cannot be animated, a non-finite time or rate is refused.
    let vox = text.replace("bunny.obj", "chr_knight.vox");
    let bad = dir.path().join("vox.ron");
    std::fs::write(&bad, vox).unwrap();
    let out = render(&bad, "0", &dir.path().join("x.png"), &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("animate needs a mesh model"),
        "{err}"
    );
    let out = render(&scene, "NaN", &dir.path().join("x.png"), &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--time must be a finite"),
        "{err}"
    );
    let nan = text.replace("degrees_per_second: 90.0", "degrees_per_second: inf");
    std::fs::write(&bad, nan).unwrap();
    let out = render(&bad, "0", &dir.path().join("x.png"), &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("objects[0].animate: Twist degrees_per_second"),
        "{err}"
    );
}

#[test]
fn bench_dynamic_reports_the_update_beside_the_static_frame() {
    let dir = tempfile::tempdir().unwrap();
    succeeded(
        ssbvb()
            .args([
                "bench", "--preset", "dynamic", "--levels", "5", "--sizes", "64x48",
            ])
            .args(["--frames", "1", "--out"])
            .arg(dir.path()),
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("dynamic.json")).unwrap())
            .unwrap();
    let row = &json["rows"][0];
    assert_eq!(row["level"], 5);
    for key in [
        "static_frame_ms",
        "update_ms",
        "voxelize_ms",
        "lod_ms",
        "animated_frame_ms",
        "cpu_update_ms",
    ] {
        assert!(row[key].as_f64().unwrap() > 0.0, "{key}: {row}");
    }
    assert!(row["voxels"].as_u64().unwrap() > 1000, "{row}");
    assert!(row["edit_ms"].as_f64().unwrap() > 0.0, "{row}");
    assert!(row["edit_removed"].as_u64().unwrap() > 10, "{row}");
    for f in ["dynamic.csv", "dynamic.md"] {
        assert!(dir.path().join(f).is_file(), "{f}");
    }
}
