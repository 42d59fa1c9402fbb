//! `--time-submissions`: each GPU submission timed alone, the longest per kind listed
//! (`docs/reliability.md`, "Long submissions").

use super::{ssbvb, stdout_json, succeeded};

#[test]
fn render_lists_its_submissions_longest_first() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    let render = |extra: &[&str]| {
        let out = succeeded(
            ssbvb()
                .args(["render", "--size", "64x48", "--json", "-o"])
                .arg(&png)
                .args(extra),
        );
        stdout_json(&out)
    };
    let plain = render(&[]);
    assert!(plain.get("submissions").is_none(), "{plain}");
    let timed = render(&["--time-submissions", "--frames", "3"]);
    let subs = timed["submissions"].as_array().unwrap();
    let kind = |what: &str| subs.iter().find(|s| s["what"] == what).cloned();
    // The warm-up, three soak frames and the written one; profiled frames also submit
    // each pass alone on this software adapter.
    let frame = kind("frame").unwrap_or_else(|| panic!("{timed}"));
    assert!(frame["count"].as_u64().unwrap() >= 5, "{frame}");
    assert!(kind("texture readback").is_some(), "{timed}");
    let maxes: Vec<f64> = subs.iter().map(|s| s["max_ms"].as_f64().unwrap()).collect();
    assert!(maxes.windows(2).all(|w| w[0] >= w[1]), "{maxes:?}");
    for s in subs {
        let (max, total) = (
            s["max_ms"].as_f64().unwrap(),
            s["total_ms"].as_f64().unwrap(),
        );
        assert!(max > 0.0 && total >= max, "{s}");
    }
}
