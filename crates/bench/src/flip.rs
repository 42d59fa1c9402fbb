//! FLIP (Andersson et al. 2020: NVIDIA's perceptual error between a rendered image and its
//! reference, 0 = identical, 1 = as different as can be) through the `nv-flip` crate,
//! which builds NVIDIA's reference C++ code. A test holds it to the value NVIDIA's own
//! Python package (`flip-evaluator` 1.7) gives for a committed pair of images.
//!
//! Both images are LDR sRGB and compared as RGB: a frame with alpha is first composited
//! over black ([`over_black`]), so a pixel a supersampled reference covers in part is
//! compared at its coverage.

use anyhow::{Result, bail};

use ssbvb_voxel::shading::{linear_to_srgb8, srgb_to_linear};

/// FLIP's default observer: 0.7 m from a 0.7 m wide monitor of 3840 pixels (67.02 pixels
/// per degree), as NVIDIA's tools assume.
pub(crate) fn default_pixels_per_degree() -> f32 {
    nv_flip::pixels_per_degree(0.7, 3840.0, 0.7)
}

/// The mean FLIP of `test` against `reference`, both RGB8 sRGB of `size`.
pub(crate) fn flip_rgb8(reference: &[u8], test: &[u8], size: (u32, u32)) -> Result<f64> {
    Ok(flip_map(reference, test, size)?.0)
}

/// [`flip_rgb8`], and the error map in NVIDIA's magma colours (RGB8), as FLIP's tools
/// show it.
pub(crate) fn flip_map_rgb8(
    reference: &[u8],
    test: &[u8],
    size: (u32, u32),
) -> Result<(f64, Vec<u8>)> {
    let (mean, map) = flip_map(reference, test, size)?;
    let magma = map.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    Ok((mean, magma))
}

fn flip_map(
    reference: &[u8],
    test: &[u8],
    size: (u32, u32),
) -> Result<(f64, nv_flip::FlipImageFloat)> {
    let pixels = size.0 as usize * size.1 as usize;
    if reference.len() != pixels * 3 || test.len() != pixels * 3 {
        bail!(
            "FLIP: images of {} and {} bytes for {}x{} RGB pixels",
            reference.len(),
            test.len(),
            size.0,
            size.1
        );
    }
    if pixels == 0 {
        bail!("FLIP: an empty image");
    }
    let r = nv_flip::FlipImageRgb8::with_data(size.0, size.1, reference);
    let t = nv_flip::FlipImageRgb8::with_data(size.0, size.1, test);
    let map = nv_flip::flip(r, t, default_pixels_per_degree());
    let mean = map.to_vec().iter().map(|&e| e as f64).sum::<f64>() / pixels as f64;
    Ok((mean, map))
}

/// Straight-alpha RGBA8 (sRGB) composited over black, in linear light: RGB8 sRGB. Opaque
/// pixels keep their colour, transparent ones turn black.
pub(crate) fn over_black(rgba: &[u8]) -> Vec<u8> {
    rgba.chunks_exact(4)
        .flat_map(|p| {
            let a = p[3];
            let c = |v: u8| match a {
                255 => v,
                0 => 0,
                _ => linear_to_srgb8(srgb_to_linear(v as f32 / 255.0) * a as f32 / 255.0),
            };
            [c(p[0]), c(p[1]), c(p[2])]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rgb(name: &str) -> (Vec<u8>, (u32, u32)) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data")
            .join(name);
        let img = image::open(&path).unwrap().to_rgb8();
        let size = img.dimensions();
        (img.into_raw(), size)
    }

    /// `flip_reference.png` and `flip_test.png` (a gradient and a disc; the disc moved by a
    /// pixel and noise added) give 0.1147576 in NVIDIA's `flip_evaluator` 1.7 (`evaluate(ref,
    /// test, "LDR")`, its default 67.02 pixels per degree); the crate, an older release of
    /// the same C++ code, gives 0.1147575. Bound: 1e-6.
    #[test]
    fn flip_matches_nvidias_reference_implementation_on_a_known_pair() {
        let (r, size) = rgb("flip_reference.png");
        let (t, size_t) = rgb("flip_test.png");
        assert_eq!(size, size_t);
        let mean = flip_rgb8(&r, &t, size).unwrap();
        assert!(
            (mean - 0.114_757_6).abs() < 1e-6,
            "FLIP mean {mean} (NVIDIA's: 0.1147576)"
        );
        assert_eq!(flip_rgb8(&r, &r, size).unwrap(), 0.0);
        let (same, magma) = flip_map_rgb8(&r, &t, size).unwrap();
        assert_eq!((same, magma.len()), (mean, r.len()));
        assert!(flip_rgb8(&r, &t[3..], size).is_err());
        assert!(flip_rgb8(&[], &[], (0, 0)).is_err());
    }

    #[test]
    fn compositing_over_black_scales_linear_light_by_coverage() {
        let px = over_black(&[200, 100, 50, 255, 200, 100, 50, 0, 255, 255, 255, 128]);
        assert_eq!(&px[..6], &[200, 100, 50, 0, 0, 0]);
        // White at half coverage: linear 0.5 → sRGB 188.
        assert_eq!(&px[6..], &[188, 188, 188]);
    }
}
