//! An allocation the driver refuses (`--inject-fault oom@FRAME`, hidden: the next large
//! allocation is refused and the session is rebuilt at that frame). Under a `--gpu-budget`
//! the budget is halved and the frame goes on: the image is then exactly the render under
//! the lowered budget. Without one the run ends with an error naming the resource, its
//! size and the flag, and writes nothing.

use super::{ssbvb, stdout_json, succeeded};

/// Runs `render --json` at 64x48 with `args`; the report and the PNG's bytes.
fn render(dir: &std::path::Path, name: &str, args: &[&str]) -> (serde_json::Value, Vec<u8>) {
    let png = dir.join(name);
    let out = succeeded(
        ssbvb()
            .args(["render", "--size", "64x48", "--json", "-o"])
            .arg(&png)
            .args(args),
    );
    (stdout_json(&out), std::fs::read(&png).unwrap())
}

fn budget_mib(report: &serde_json::Value) -> u64 {
    report["streaming"]["budget_bytes"].as_u64().unwrap() >> 20
}

#[test]
fn a_refused_allocation_under_a_budget_halves_it_and_the_frame_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, plain_png) = render(dir.path(), "plain.png", &["--gpu-budget", "4"]);
    assert_eq!(budget_mib(&plain), 4);
    // At the first upload.
    let (first, first_png) = render(
        dir.path(),
        "first.png",
        &["--gpu-budget", "8", "--inject-fault", "oom@0"],
    );
    assert_eq!(budget_mib(&first), 4, "{first}");
    let w = first["warnings"].to_string();
    assert!(
        w.contains("out of GPU memory: the driver refused")
            && w.contains("MiB for LOD table, voxel colours and normals")
            && w.contains("--gpu-budget lowered from 8 to 4 MiB"),
        "{w}"
    );
    assert!(
        first_png == plain_png,
        "not the image of the lowered budget"
    );
    // In a soak: rebuilt at frame 11, the soak goes on; its written frame too is the
    // lowered budget's, and the device holds no more than before the rebuild.
    let (soak, soak_png) = render(
        dir.path(),
        "soak.png",
        &[
            "--gpu-budget",
            "8",
            "--frames",
            "24",
            "--inject-fault",
            "oom@11",
        ],
    );
    let s = &soak["soak"];
    assert_eq!(s["out_of_memory_rebuilds"], 1, "{soak}");
    assert_eq!(s["device_recoveries"], 0, "{soak}");
    assert_eq!(budget_mib(&soak), 4, "{soak}");
    assert!(
        soak["warnings"]
            .to_string()
            .contains("soak frame 11: out of GPU memory"),
        "{soak}"
    );
    assert!(
        soak_png == plain_png,
        "the soak's last frame is not the lowered budget's"
    );
    assert!(
        s["end"]["gpu_bytes"].as_u64() <= s["start"]["gpu_bytes"].as_u64(),
        "{s}"
    );
}

#[test]
fn a_refused_allocation_without_a_budget_names_the_resource_and_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    for (args, want) in [
        (
            &["--inject-fault", "oom@0"][..],
            "the scene does not fit the GPU's memory; run with --gpu-budget MIB",
        ),
        (
            &["--frames", "12", "--inject-fault", "oom@7"][..],
            "rebuilding the GPU session at soak frame 7 (oom@7)",
        ),
        (
            &["--gpu-budget", "1", "--inject-fault", "oom@0"][..],
            "even under a 1 MiB budget",
        ),
    ] {
        let out = ssbvb()
            .args(["render", "--size", "64x48", "-o"])
            .arg(&png)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(
            err.contains("out of GPU memory: the driver refused")
                && err.contains("for LOD table, voxel colours and normals 0"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!png.exists(), "{args:?}: an image was written");
    }
}

/// `bench --inject-fault oom@ROW`: that row fails with the resource named and the rows
/// after it are measured.
#[test]
fn bench_reports_the_row_whose_allocation_was_refused_and_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let out = succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .args([
                "bench",
                "--levels",
                "5",
                "--sizes",
                "64x48",
                "--techniques",
                "ssbvb-unique,octree",
                "--frames",
                "1",
                "--json",
                "--inject-fault",
                "oom@0",
                "--out",
            ])
            .arg(dir.path().join("b")),
    );
    let json = stdout_json(&out);
    let rows: Vec<&str> = json["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["technique"].as_str().unwrap())
        .collect();
    assert_eq!(rows, ["octree"], "{json}");
    let failed = json["failed"].as_array().unwrap();
    assert_eq!(failed.len(), 1, "{json}");
    let why = failed[0].as_str().unwrap();
    assert!(
        why.starts_with("ssbvb-unique on bunny.obj level 5")
            && why.contains("out of GPU memory: the driver refused"),
        "{why}"
    );
}

/// A refused frame target (the scene's streams of a level-3 bunny are all smaller than
/// the injection's 64 KiB) is not the budget's to fix: an error naming `--size`, the
/// budget left alone.
#[test]
fn a_refused_frame_target_names_the_size_not_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    let out = ssbvb()
        .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
        .args(["render", "assets/models/bunny.obj"])
        .args(["--level", "3", "--size", "320x240", "--gpu-budget", "8"])
        .args(["--inject-fault", "oom@0", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("the frame's targets do not fit the GPU's memory")
            && err.contains("--size")
            && err.contains("(physical ")
            && !err.contains("lowered"),
        "{err}"
    );
    assert!(!err.contains("panicked") && !png.exists(), "{err}");
}
