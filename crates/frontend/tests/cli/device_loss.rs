//! Losing the GPU device during a soak (`render --frames N --inject-fault
//! device-lost@FRAME`, hidden): the soak opens a new device and session from the CPU-side
//! state, draws the lost frame again and ends on the image of a run without the fault, with
//! the device's memory flat; a device lost again within a few frames is an error, not a
//! retry loop.

use super::{ssbvb, stdout_json, succeeded};

/// Runs `render` with `args` and returns the report and the PNG's bytes.
fn render(dir: &std::path::Path, name: &str, args: &[&str]) -> (serde_json::Value, Vec<u8>) {
    let png = dir.join(name);
    let out = succeeded(
        ssbvb()
            .args(["render", "--json", "-o"])
            .arg(&png)
            .args(args),
    );
    (stdout_json(&out), std::fs::read(&png).unwrap())
}

#[test]
fn a_soak_recovers_from_twenty_lost_devices_and_ends_on_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let soak = ["--size", "32x24", "--frames", "200"];
    let (clean, clean_png) = render(dir.path(), "clean.png", &soak);
    assert_eq!(clean["device_recoveries"], 0, "{clean}");
    // 20 losses at frames 8 to 10 apart (more than `LOST_AGAIN_WITHIN`), from frame 3.
    let mut frames = Vec::new();
    let mut f = 3;
    for k in 1..=20 {
        frames.push(format!("device-lost@{f}"));
        f += 8 + (k * 7) % 3;
    }
    let mut args: Vec<&str> = soak.to_vec();
    for f in &frames {
        args.extend(["--inject-fault", f.as_str()]);
    }
    let (lost, lost_png) = render(dir.path(), "lost.png", &args);
    assert_eq!(lost["device_recoveries"], 20, "{lost}");
    assert_eq!(lost["soak"]["device_recoveries"], 20, "{lost}");
    assert!(
        lost_png == clean_png,
        "the last frame differs after recovering"
    );
    // The new device holds what the lost one held. The process grows by what the driver
    // keeps of each device it made (lavapipe, measured: 11 % over the 19 recoveries after
    // the start sample, ~3 MiB each on ~190 MiB).
    let s = &lost["soak"];
    for key in ["gpu_bytes", "buffers", "bind_groups"] {
        assert_eq!(s["start"][key], s["end"][key], "{key}: {s}");
    }
    let rss = s["rss_growth_percent"].as_f64().unwrap();
    assert!(rss < 30.0, "{s}");
}

#[test]
fn a_budgeted_soak_recovers_with_its_pages_streamed_again() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["--size", "64x48", "--gpu-budget", "8", "--frames", "24"];
    let (_, clean) = render(dir.path(), "clean.png", &args);
    let mut faults = args.to_vec();
    faults.extend(["--inject-fault", "device-lost@11"]);
    let (lost, png) = render(dir.path(), "lost.png", &faults);
    assert_eq!(lost["device_recoveries"], 1, "{lost}");
    assert!(
        png == clean,
        "the last frame differs after recovering under a budget"
    );
}

#[test]
fn repeated_losses_and_faults_outside_the_soak_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    for (args, want) in [
        (
            &[
                "--frames",
                "30",
                "--inject-fault",
                "device-lost@10",
                "--inject-fault",
                "device-lost@12",
            ][..],
            "lost again at frame 12",
        ),
        (
            &["--inject-fault", "device-lost@2"][..],
            "--frames 3 or more",
        ),
        (
            &["--frames", "5", "--inject-fault", "device-lost@5"][..],
            "--frames 6 or more",
        ),
        (
            &["--frames", "5", "--inject-fault", "leak@1"][..],
            "unknown fault `leak`",
        ),
        (
            &["--frames", "5", "--inject-fault", "oom@5"][..],
            "--inject-fault oom@5 needs a soak of more than 5 frames (--frames 6 or more)",
        ),
    ] {
        let out = ssbvb()
            .args(["render", "--size", "32x24", "-o"])
            .arg(&png)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(want),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// `bench`: the row whose device is lost is reported failed with the reason, and the rows
/// after it are measured on a new device; a loss on the next row too ends the run.
#[test]
fn bench_reports_the_row_that_lost_the_device_and_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let bench = [
        "bench",
        "--levels",
        "5",
        "--sizes",
        "64x48",
        "--techniques",
        "ssbvb-unique,esvo,octree",
        "--frames",
        "1",
        "--json",
        "--out",
    ];
    let out = succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .args(bench)
            .arg(dir.path().join("one"))
            .args(["--inject-fault", "device-lost@1"]),
    );
    let json = stdout_json(&out);
    let rows: Vec<&str> = json["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["technique"].as_str().unwrap())
        .collect();
    assert_eq!(rows, ["ssbvb-unique", "octree"], "{json}");
    let failed = json["failed"].as_array().unwrap();
    assert_eq!(failed.len(), 1, "{json}");
    let why = failed[0].as_str().unwrap();
    assert!(
        why.starts_with("esvo on bunny.obj level 5") && why.contains("device was lost"),
        "{why}"
    );
    let again = ssbvb()
        .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
        .args(bench)
        .arg(dir.path().join("two"))
        .args([
            "--inject-fault",
            "device-lost@1",
            "--inject-fault",
            "device-lost@2",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(
        !again.status.success() && err.contains("lost again"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}
