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
        ("vox", "9", "256³ cells per model"),
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
