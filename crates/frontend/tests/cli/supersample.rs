//! `render --reference --samples N`: the supersampled reference as users run it.

use super::{ssbvb, stdout_json, succeeded};

/// Alphas of a PNG written by `render`.
fn alphas(path: &std::path::Path) -> Vec<u8> {
    let img = image::open(path).unwrap().to_rgba8();
    img.pixels().map(|p| p.0[3]).collect()
}

#[test]
fn the_supersampled_reference_covers_silhouette_pixels_partly() {
    let dir = tempfile::tempdir().unwrap();
    let mut coverage = Vec::new();
    for samples in ["1", "16", "8"] {
        let png = dir.path().join(format!("ref{samples}.png"));
        let out = succeeded(
            ssbvb()
                .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
                .args(["render", "assets/models/bunny.obj", "--reference"])
                .args(["--samples", samples])
                .args(["--level", "5", "--size", "48x36", "--json", "-o"])
                .arg(&png),
        );
        let r = stdout_json(&out);
        assert_eq!(r["mode"], "reference");
        assert_eq!(r["samples"].to_string(), samples);
        let a = alphas(&png);
        let partial = a.iter().filter(|&&v| v != 0 && v != 255).count();
        let sum: f64 = a.iter().map(|&v| v as f64 / 255.0).sum();
        coverage.push((partial, sum));
    }
    // One sample: every pixel in or out. Sixteen (4 x 4 strata) and eight (4 x 2): the
    // silhouette's pixels in between.
    assert_eq!(coverage[0].0, 0);
    assert!(coverage[1].0 > 20 && coverage[2].0 > 20, "{coverage:?}");
    // The same object's area either way (to a few percent: the silhouette's pixels are
    // counted whole or not at one sample).
    let one = coverage[0].1;
    for (_, many) in &coverage[1..] {
        assert!((one - many).abs() < 0.05 * one, "{coverage:?}");
    }
}

#[test]
fn sample_counts_out_of_range_or_not_for_the_reference_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("never.png");
    for (args, want) in [
        (
            &["--reference", "--samples", "0"][..],
            "from 1 to 1024, got 0",
        ),
        (
            &["--reference", "--samples", "1025"][..],
            "from 1 to 1024, got 1025",
        ),
        (&["--samples", "4"][..], "applies to --reference only"),
    ] {
        let out = ssbvb()
            .arg("render")
            .args(args)
            .arg("-o")
            .arg(&png)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(want),
            "{args:?}: {err}"
        );
        assert!(!png.exists(), "{args:?}");
    }
}
