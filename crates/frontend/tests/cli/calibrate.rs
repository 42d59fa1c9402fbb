//! `ssbvb calibrate` and the default pipeline it sets: each SSBVB form measured on this
//! adapter is stored fastest first beside the asset cache, and `render` then uses the
//! fastest for exactly this adapter, driver and limits; another driver's or other limits'
//! entry is never used, and a corrupt file is ignored with a warning (the rule chooses).

use super::{ssbvb, stdout_json, succeeded};

#[test]
fn calibration_sets_the_default_form_for_its_own_adapter_only() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let file = cache.join("calibration.json");
    let run = |args: &[&str]| {
        let mut c = ssbvb();
        c.env("SSBVB_CACHE_DIR", &cache).args(args);
        c.arg("-o").arg(dir.path().join("x.png"));
        let out = succeeded(&mut c);
        (
            stdout_json(&out),
            String::from_utf8_lossy(&out.stderr).to_string(),
        )
    };
    let render = |extra: &[&str]| {
        let mut args = vec!["render", "--size", "32x24", "--json"];
        args.extend_from_slice(extra);
        run(&args)
    };
    let out = succeeded(ssbvb().env("SSBVB_CACHE_DIR", &cache).args([
        "calibrate",
        "--size",
        "32x24",
        "--frames",
        "1",
    ]));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("calibrated llvmpipe") && stdout.contains("wrote"),
        "{stdout}"
    );
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    let entry = &json["entries"][0];
    // Lavapipe runs all six forms; each was timed.
    let forms = entry["forms"].as_array().unwrap();
    assert_eq!(forms.len(), 6, "{json}");
    assert!(
        forms.iter().all(|f| f["frame_ms"].as_f64().unwrap() > 0.0),
        "{json}"
    );
    assert_eq!(entry["adapter"]["limits"], "adapter");

    // Make the raster form the measured fastest: render follows the file, not the rule.
    let raster = serde_json::json!({"pipeline": "pipelines/ssbvb_unique.ron", "frame_ms": 0.001, "clock": "wall"});
    json["entries"][0]["forms"]
        .as_array_mut()
        .unwrap()
        .insert(0, raster);
    std::fs::write(&file, serde_json::to_string(&json).unwrap()).unwrap();
    let (report, _) = render(&[]);
    let choice = &report["pipeline_choice"];
    assert_eq!(choice["by"], "calibration", "{report}");
    assert!(
        report["pipeline"]
            .as_str()
            .unwrap()
            .ends_with("pipelines/ssbvb_unique.ron")
            && choice["reason"]
                .as_str()
                .unwrap()
                .contains("ssbvb calibrate"),
        "{report}"
    );
    // Measured under the adapter's own limits: not used under WebGPU's.
    let (report, _) = render(&["--limits", "webgpu"]);
    assert_eq!(report["pipeline_choice"]["by"], "adapter", "{report}");
    // Another driver version's entry is never used.
    let mut other = json.clone();
    other["entries"][0]["adapter"]["driver"] = "llvmpipe Mesa 1.0".into();
    std::fs::write(&file, serde_json::to_string(&other).unwrap()).unwrap();
    let (report, _) = render(&[]);
    assert_eq!(report["pipeline_choice"]["by"], "adapter", "{report}");
    assert!(
        report["pipeline"]
            .as_str()
            .unwrap()
            .ends_with("pipelines/ssbvb_direct.ron"),
        "{report}"
    );
    // A corrupt file: a warning, the rule's choice, and the frame still drawn.
    std::fs::write(&file, "{\"version\": 1, \"entries\": [").unwrap();
    let (report, stderr) = render(&[]);
    assert_eq!(report["pipeline_choice"]["by"], "adapter", "{report}");
    assert!(
        stderr.contains("warning: the calibration was ignored")
            && stderr.contains("calibration.json")
            && report["pipeline_choice"]["reason"]
                .as_str()
                .unwrap()
                .contains("calibration was ignored"),
        "{stderr}"
    );
    assert!(report["covered_pixels"].as_u64().unwrap() > 50, "{report}");
}
