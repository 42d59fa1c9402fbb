//! `ssbvb render --voxel-mask PNG` (the coverage the web page's browser test compares): a
//! black-and-white image whose white pixels are exactly the frame's voxel pixels, as
//! `render --json` counts them; a pipeline without a stencil and the CPU reference say why
//! they have none.

use super::{ssbvb, stdout_json, succeeded};

#[test]
fn the_voxel_mask_is_the_counted_voxel_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let (png, mask) = (dir.path().join("f.png"), dir.path().join("m.png"));
    let out = succeeded(
        ssbvb()
            .args(["render", "--size", "64x48", "--json", "-o"])
            .arg(&png)
            .arg("--voxel-mask")
            .arg(&mask),
    );
    let json = stdout_json(&out);
    let counted = json["voxel_pixels"].as_u64().unwrap();
    let m = image::open(&mask).unwrap().to_luma8();
    assert_eq!((m.width(), m.height()), (64, 48));
    assert!(m.pixels().all(|p| p[0] == 0 || p[0] == 255));
    let white = m.pixels().filter(|p| p[0] == 255).count() as u64;
    assert_eq!(white, counted, "{json}");
    // The bunny covers part of the frame, not all of it, and the ground is not a voxel.
    assert!(counted > 200 && counted < 64 * 48 / 2, "{counted}");

    let out = ssbvb()
        .args(["render", "--reference", "--size", "16x12", "-o"])
        .arg(dir.path().join("r.png"))
        .arg("--voxel-mask")
        .arg(&mask)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--voxel-mask reads a GPU frame's stencil"),
        "{err}"
    );
}
