//! `ssbvb export`: each format written with `--json`'s report, loadable again (`ssbvb
//! render` draws the VOX, raw and OBJ files it wrote), and an export over a format's limit
//! refused before anything is voxelized or written. The formats' round trips are
//! `ssbvb_voxel::export`'s tests.

use super::{ssbvb, stdout_json, succeeded};

#[test]
fn each_format_is_written_and_renders_again() {
    let dir = tempfile::tempdir().unwrap();
    for (format, extra, ext) in [
        ("vox", None, "vox"),
        ("raw", None, "raw"),
        ("npy", None, "npy"),
        ("npy", Some("--sparse"), "npy"),
        ("obj", None, "obj"),
    ] {
        let out = dir
            .path()
            .join(format!("bunny_{format}{}.{ext}", extra.unwrap_or("")));
        let mut c = ssbvb();
        c.args([
            "export",
            "assets/models/bunny.obj",
            "--level",
            "5",
            "--format",
            format,
            "--json",
            "-o",
        ])
        .arg(&out);
        if let Some(e) = extra {
            c.arg(e);
        }
        let json = stdout_json(&succeeded(&mut c));
        assert!(json["voxels"].as_u64().unwrap() > 1000, "{json}");
        assert_eq!(
            json["bytes"].as_u64().unwrap(),
            std::fs::metadata(&out).unwrap().len()
        );
        if ext != "npy" {
            let png = dir.path().join(format!("{format}.png"));
            succeeded(
                ssbvb()
                    .arg("render")
                    .arg(&out)
                    .args(["--level", "5", "--size", "32x24", "-o"])
                    .arg(&png),
            );
        }
    }
    for (format, level, want) in [
        ("vox", "13", "4096³ cells"),
        ("npy", "11", "--sparse"),
        ("raw", "11", "coarser --level"),
    ] {
        let out = dir.path().join(format!("big.{format}"));
        let o = ssbvb()
            .args([
                "export",
                "assets/models/bunny.obj",
                "--level",
                level,
                "--format",
                format,
                "-o",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(want), "{format}: {err}");
        assert!(!out.exists());
    }
}

/// A prepared asset file (what `voxelize -o` and the viewer's save write) is a model:
/// `render` draws it at its finest level, a finer `--level` is refused naming what it
/// holds, and its export is byte for byte the export of the model it was prepared from.
/// A write that fails part-way (the file size limit of a full disk: `ulimit -f`, with
/// SIGXFSZ ignored so the write returns EFBIG) names the file and leaves the previous
/// export whole, with no temporary file behind.
#[test]
fn a_prepared_asset_file_is_a_model_and_a_failed_write_keeps_the_previous_file() {
    let dir = tempfile::tempdir().unwrap();
    let asset = dir.path().join("bunny.ssbvb");
    succeeded(
        ssbvb()
            .args(["voxelize", "assets/models/bunny.obj", "--level", "5", "-o"])
            .arg(&asset),
    );
    let o = succeeded(
        ssbvb()
            .arg("render")
            .arg(&asset)
            .args(["--size", "32x24", "-o"])
            .arg(dir.path().join("a.png")),
    );
    let log = String::from_utf8_lossy(&o.stdout);
    assert!(log.contains("prepared asset file, read as it is"), "{log}");
    let o = ssbvb()
        .arg("render")
        .arg(&asset)
        .args(["--level", "6", "-o"])
        .arg(dir.path().join("b.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("levels 0..=5; level 6 is finer"),
        "{err}"
    );
    let export = |model: &std::path::Path, out: &std::path::Path| {
        succeeded(
            ssbvb()
                .arg("export")
                .arg(model)
                .args(["--level", "5", "--format", "npy", "--sparse", "-o"])
                .arg(out),
        );
        std::fs::read(out).unwrap()
    };
    let (from_asset, from_model) = (dir.path().join("a.npy"), dir.path().join("m.npy"));
    assert_eq!(
        export(&asset, &from_asset),
        export(std::path::Path::new("assets/models/bunny.obj"), &from_model)
    );

    let target = dir.path().join("dense.npy");
    std::fs::write(&target, b"the previous export").unwrap();
    let o = std::process::Command::new("sh")
        .current_dir(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f 16; exec '{}' export assets/models/bunny.obj --level 5 \
             --format npy -o '{}'",
            env!("CARGO_BIN_EXE_ssbvb"),
            target.display()
        ))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("File too large"),
        "{err}"
    );
    assert_eq!(std::fs::read(&target).unwrap(), b"the previous export");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("tmp") || n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}
