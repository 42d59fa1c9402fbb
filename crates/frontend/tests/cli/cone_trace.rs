//! Voxel cone tracing from the command line: `pipeline check` names the pass and the knob
//! out of range, and `render --pipeline assets/pipelines/ssbvb_vct.ron` lights the bundled
//! default scene (the bunny's contact shadow darkens the plane under it).

use super::{pass_names, ssbvb, stdout_json, succeeded};

const VCT: &str = include_str!("../../../../assets/pipelines/ssbvb_vct.ron");

#[test]
fn pipeline_check_rejects_each_cone_knob_out_of_range_by_name() {
    super::assert_knobs_refused(
        VCT,
        "cone_trace",
        "ConeTrace",
        &[
            ("cones: 9", "cones: 0", "cones"),
            ("aperture: 60.0", "aperture: 0.0", "aperture"),
            ("aperture: 60.0", "aperture: 180.0", "aperture"),
            (
                "shadow_aperture: 6.0",
                "shadow_aperture: -2.0",
                "shadow_aperture",
            ),
            ("max_distance: 0.5", "max_distance: -1.0", "max_distance"),
            ("step_scale: 1.0", "step_scale: 0.0", "step_scale"),
            ("resolution: 128", "resolution: 4", "resolution"),
        ],
    );
}

/// Mean sRGB value of the pixels in rows `y0..y1` of the middle third of the columns.
fn mean_band(img: &image::RgbaImage, y0: u32, y1: u32) -> f64 {
    let (w, _) = img.dimensions();
    let mut sum = 0.0;
    let mut n = 0.0;
    for y in y0..y1 {
        for x in w / 3..2 * w / 3 {
            let p = img.get_pixel(x, y);
            sum += f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2]);
            n += 3.0;
        }
    }
    sum / n
}

#[test]
fn the_default_scene_renders_with_cone_traced_light() {
    let dir = tempfile::tempdir().unwrap();
    let render = |pipeline: &str, name: &str| {
        let png = dir.path().join(name);
        let out = succeeded(
            ssbvb()
                .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
                .args([
                    "render",
                    "--size",
                    "128x96",
                    "--json",
                    "--pipeline",
                    pipeline,
                    "-o",
                ])
                .arg(&png),
        );
        let json = stdout_json(&out);
        (image::open(&png).unwrap().to_rgba8(), json)
    };
    let (lit, json) = render("assets/pipelines/ssbvb_vct.ron", "vct.png");
    let passes = pass_names(&json);
    assert!(passes.iter().any(|p| p == "cone_trace"), "{passes:?}");
    let (plain, _) = render("assets/pipelines/ssbvb_unique.ron", "plain.png");
    // The plane just under the bunny's feet (rows 83..92 of 96 in the default view) is
    // darker with ambient occlusion; the background stays untouched.
    let (a, b) = (mean_band(&lit, 83, 92), mean_band(&plain, 83, 92));
    assert!(a < b - 3.0, "contact shadow: {a} vs {b}");
    let empty = |img: &image::RgbaImage| img.pixels().map(|p| p[3] == 0).collect::<Vec<_>>();
    assert_eq!(empty(&lit), empty(&plain));
    assert!(empty(&lit).iter().any(|&e| e));
}
