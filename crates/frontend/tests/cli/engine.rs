//! `ssbvb render` on the engine: a library program drawing a scene through
//! `ssbvb-engine`'s API writes the bytes `render` writes, and what a model's load could
//! not do (a missing material or texture) reaches the report as warnings naming the file.

use std::path::Path;

use ssbvb_engine::{Content, Engine, RenderOptions};
use ssbvb_voxel::progress::NoProgress;

use crate::{ssbvb, succeeded};

/// The decoded RGBA8 pixels of a PNG.
fn pixels(path: &Path) -> Vec<u8> {
    image::open(path).unwrap().to_rgba8().into_raw()
}

/// What the engine's front-page program (and `examples/render_scene.rs`) does, in this
/// process, against `ssbvb render` of the same scene and size on the same adapter.
#[test]
fn a_program_on_the_engine_writes_what_render_writes() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let cli = dir.path().join("cli.png");
    succeeded(ssbvb().args(["render", "--size", "80x60", "-o"]).arg(&cli));
    let content =
        Content::open(&root.join("assets/scenes/default.ron"), None, &NoProgress).unwrap();
    let mut engine = Engine::open(
        content,
        &RenderOptions {
            size: (80, 60),
            ..RenderOptions::default()
        },
    )
    .unwrap();
    engine.render().unwrap();
    let lib = dir.path().join("lib.png");
    engine.save_png(&lib).unwrap();
    let (a, b) = (pixels(&cli), pixels(&lib));
    assert_eq!(a.len(), 80 * 60 * 4);
    assert!(
        a.chunks(4).filter(|p| p[3] > 0).count() > 1000,
        "an empty frame"
    );
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert_eq!(
        differ,
        0,
        "{differ} bytes differ ({})",
        engine.choice().pipeline
    );
}

/// An OBJ whose `mtllib` is missing and whose MTL names a missing texture renders, and says
/// both in `render`'s output and `--json` `warnings`, on a rebuild and on a cache hit.
#[test]
fn a_missing_material_or_texture_is_a_warning_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("m.obj");
    std::fs::write(
        &obj,
        "mtllib gone.mtl\nmtllib here.mtl\nusemtl red\nv -1 -1 -1\nv 1 -1 0\nv 0 1 1\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("here.mtl"),
        "newmtl red\nKd 1 0 0\nmap_Kd missing.png\n",
    )
    .unwrap();
    let cache = dir.path().join("cache");
    for pass in ["rebuilt", "cache hit"] {
        let out = succeeded(
            ssbvb()
                .env("SSBVB_CACHE_DIR", &cache)
                .args(["render", "--level", "4", "--size", "32x24", "--json", "-o"])
                .arg(dir.path().join("m.png"))
                .arg(&obj),
        );
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let warnings: Vec<String> = report["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w.as_str().unwrap().to_string())
            .collect();
        for file in ["gone.mtl", "missing.png"] {
            assert!(
                warnings.iter().any(|w| w.contains(file)),
                "{pass}: no warning names {file}: {warnings:?}"
            );
        }
    }
    let out = succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", &cache)
            .args(["render", "--level", "4", "--size", "32x24", "-o"])
            .arg(dir.path().join("m.png"))
            .arg(&obj),
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.lines()
            .any(|l| l.starts_with("warning: ") && l.contains("missing.png")),
        "{text}"
    );
}
