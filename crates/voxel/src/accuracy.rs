//! Accuracy of a GPU technique against the CPU reference (`docs/architecture.md`, "Accuracy:
//! the CPU reference").
//!
//! A technique reports, per pixel, the voxel it shows ([`GpuHit`]: instance, cell, ray
//! distance and normal) or nothing. [`compare`] measures it against a [`ReferenceImage`] of
//! the same view:
//!
//! - **coverage**: pixels covered by the reference, by the GPU, by both, and their
//!   intersection over union (1 when both cover exactly the same pixels);
//! - **same-voxel rate**: among pixels covered by both, the fraction that show the same
//!   voxel (same instance, same cell);
//! - **depth error in voxels**: among pixels covered by both, `|t_gpu − t_ref|` divided by
//!   the world size of one cell of the reference hit's instance (a parameter per instance:
//!   the LOD level and the instance scale decide it);
//! - **normal error in degrees**: among pixels covered by both, the angle between the GPU
//!   normal and the reference's entered-face normal (both world space; a zero or non-finite
//!   GPU normal counts as 180°).
//!
//! [`psnr_rgba8`] compares two shaded images. Every report serializes with serde.

use serde::Serialize;

use crate::reference::ReferenceImage;

/// What a GPU technique shows at one pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpuHit {
    /// Instance index, in the reference's numbering (the order of the instances given to
    /// [`crate::reference::render`]).
    pub instance: u32,
    /// The voxel's cell in the instance's LOD grid.
    pub cell: [u32; 3],
    /// World distance from the eye along the pixel's normalized ray.
    pub t: f64,
    /// World-space normal shown (the entered face's, for techniques that know it).
    pub normal: [f32; 3],
}

/// Fills in the voxel of each hit of a face rasterizer (the cube rasterizer, RastaVox),
/// whose G-buffer holds no voxel id: the cell half a cell behind the hit point
/// (`eye + t · dir` along the pixel's ray of `camera` at `size`) against the shown normal,
/// in the first of `placed` (object → world, lookup) whose level holds a voxel there. The
/// instance is the index in `placed`; hits no placed level explains keep theirs.
pub fn recover_face_voxels(
    hits: &mut [Option<GpuHit>],
    camera: &crate::camera::Camera,
    size: (u32, u32),
    placed: &[(glam::DAffine3, &crate::lookup::SparseLookup)],
) {
    let rays = camera.pixel_rays(size.0, size.1);
    let inverse: Vec<glam::DAffine3> = placed.iter().map(|(xf, _)| xf.inverse()).collect();
    for (i, hit) in hits.iter_mut().enumerate() {
        let Some(hit) = hit else { continue };
        let (x, y) = ((i % size.0 as usize) as u32, (i / size.0 as usize) as u32);
        let (o, d) = rays.ray(x, y);
        let world = o + d * hit.t;
        let n = glam::DVec3::from(hit.normal.map(f64::from));
        for (pi, ((xf, lookup), inv)) in placed.iter().zip(&inverse).enumerate() {
            let level = lookup.level;
            let s = crate::model::cell_size(level);
            // Normals go world → object with the transpose of the linear part.
            let n_obj = xf.matrix3.transpose().mul_vec3(n).normalize_or_zero();
            let q = (inv.transform_point3(world) - n_obj * (0.5 * s) + 1.0) / s;
            if q.min_element() < 0.0 || q.max_element() >= (1u64 << level) as f64 {
                continue;
            }
            let cell = [q.x as u32, q.y as u32, q.z as u32];
            if lookup.get(cell).is_some() {
                hit.instance = pi as u32;
                hit.cell = cell;
                break;
            }
        }
    }
}

/// Median, 95th percentile and maximum of a set of errors (all 0 when it is empty).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct ErrorStats {
    /// How many values.
    pub count: usize,
    /// Median (nearest rank).
    pub median: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest value.
    pub max: f64,
}

impl ErrorStats {
    /// Statistics of `values` (NaNs sort last and so count as the largest errors).
    pub fn of(mut values: Vec<f64>) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        values.sort_by(|a, b| a.total_cmp(b));
        let rank = |q: f64| {
            // Nearest rank: the smallest value with at least q of the values at or below it.
            let i = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len()) - 1;
            values[i]
        };
        Self {
            count: values.len(),
            median: rank(0.5),
            p95: rank(0.95),
            max: values[values.len() - 1],
        }
    }
}

/// The accuracy of one GPU image against the reference.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AccuracyReport {
    /// Pixels in the image.
    pub pixels: usize,
    /// Pixels the reference covers.
    pub covered_reference: usize,
    /// Pixels the GPU covers.
    pub covered_gpu: usize,
    /// Pixels both cover.
    pub covered_both: usize,
    /// `covered_both / (pixels either covers)`; 1 when neither covers any pixel.
    pub coverage_iou: f64,
    /// Among pixels both cover, the fraction showing the same voxel (instance and cell);
    /// 1 when there are none.
    pub same_voxel_rate: f64,
    /// Among pixels both cover, `|t_gpu − t_ref|` in cells of the reference instance.
    pub depth_error_voxels: ErrorStats,
    /// Among pixels both cover, the normal angle error in degrees.
    pub normal_error_deg: ErrorStats,
}

/// Errors of [`compare`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AccuracyError {
    /// The GPU image does not have one entry per reference pixel.
    #[error("the GPU result has {gpu} pixels, the reference {reference}")]
    SizeMismatch {
        /// GPU pixel count.
        gpu: usize,
        /// Reference pixel count.
        reference: usize,
    },
    /// A reference hit names an instance without a cell size.
    #[error("no cell size given for instance {0}")]
    MissingCellSize(u32),
    /// A cell size is not a positive finite number.
    #[error("cell size of instance {instance} is {size}, not a positive number")]
    BadCellSize {
        /// Instance.
        instance: usize,
        /// The size given.
        size: f64,
    },
}

/// Compares `gpu` (row-major, one entry per pixel, row 0 at the top) with `reference`.
/// `cell_size_world[i]` is the world size of one cell of instance `i` (its LOD level and
/// scale), the unit of the depth error.
pub fn compare(
    reference: &ReferenceImage,
    gpu: &[Option<GpuHit>],
    cell_size_world: &[f64],
) -> Result<AccuracyReport, AccuracyError> {
    if gpu.len() != reference.hits.len() {
        return Err(AccuracyError::SizeMismatch {
            gpu: gpu.len(),
            reference: reference.hits.len(),
        });
    }
    if let Some((instance, &size)) = cell_size_world
        .iter()
        .enumerate()
        .find(|(_, s)| !(s.is_finite() && **s > 0.0))
    {
        return Err(AccuracyError::BadCellSize { instance, size });
    }
    let (mut covered_reference, mut covered_gpu, mut both, mut same) = (0, 0, 0, 0);
    let mut depth = Vec::new();
    let mut normal = Vec::new();
    for (r, g) in reference.hits.iter().zip(gpu) {
        covered_reference += r.is_some() as usize;
        covered_gpu += g.is_some() as usize;
        let (Some(r), Some(g)) = (r, g) else { continue };
        both += 1;
        same += (r.instance == g.instance && r.cell == g.cell) as usize;
        let cell = *cell_size_world
            .get(r.instance as usize)
            .ok_or(AccuracyError::MissingCellSize(r.instance))?;
        depth.push((g.t - r.t).abs() / cell);
        normal.push(angle_deg(g.normal, r.face_normal));
    }
    let union = covered_reference + covered_gpu - both;
    Ok(AccuracyReport {
        pixels: reference.hits.len(),
        covered_reference,
        covered_gpu,
        covered_both: both,
        coverage_iou: if union == 0 {
            1.0
        } else {
            both as f64 / union as f64
        },
        same_voxel_rate: if both == 0 {
            1.0
        } else {
            same as f64 / both as f64
        },
        depth_error_voxels: ErrorStats::of(depth),
        normal_error_deg: ErrorStats::of(normal),
    })
}

/// Angle between two vectors in degrees (180 when either is zero or not finite).
pub fn angle_deg(a: [f32; 3], b: [f32; 3]) -> f64 {
    let a = a.map(f64::from);
    let b = b.map(f64::from);
    let la = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let lb = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
    if !(la > 0.0 && lb > 0.0 && la.is_finite() && lb.is_finite()) {
        return 180.0;
    }
    let cos = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb);
    cos.clamp(-1.0, 1.0).acos().to_degrees()
}

/// Peak signal-to-noise ratio in dB of two RGBA8 images of equal size over their RGB
/// channels (alpha ignored; peak 255). Identical images give `f64::INFINITY`; images of
/// different lengths or lengths that are not whole pixels give `None`.
pub fn psnr_rgba8(a: &[u8], b: &[u8]) -> Option<f64> {
    if a.len() != b.len() || !a.len().is_multiple_of(4) {
        return None;
    }
    if a.is_empty() {
        return Some(f64::INFINITY);
    }
    let mut sum = 0.0f64;
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for c in 0..3 {
            let d = pa[c] as f64 - pb[c] as f64;
            sum += d * d;
        }
    }
    let mse = sum / (a.len() / 4 * 3) as f64;
    Some(if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0 * 255.0 / mse).log10()
    })
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::reference::Hit;

    fn hit(instance: u32, cell: [u32; 3], t: f64, n: [f32; 3]) -> Hit {
        Hit {
            instance,
            voxel: 0,
            cell,
            t,
            view_depth: t,
            face_normal: n,
            position: DVec3::ZERO,
            inside: false,
        }
    }

    fn image(hits: Vec<Option<Hit>>) -> ReferenceImage {
        let n = hits.len();
        ReferenceImage {
            width: n as u32,
            height: 1,
            hits,
            colors: vec![[0.0; 4]; n],
        }
    }

    fn gpu(instance: u32, cell: [u32; 3], t: f64, normal: [f32; 3]) -> Option<GpuHit> {
        Some(GpuHit {
            instance,
            cell,
            t,
            normal,
        })
    }

    #[test]
    fn identical_results_are_perfect() {
        let z = [0.0, 0.0, 1.0];
        let r = image(vec![Some(hit(0, [1, 2, 3], 2.0, z)), None]);
        let g = vec![gpu(0, [1, 2, 3], 2.0, z), None];
        let a = compare(&r, &g, &[0.5]).unwrap();
        assert_eq!(a.pixels, 2);
        assert_eq!(
            (a.covered_reference, a.covered_gpu, a.covered_both),
            (1, 1, 1)
        );
        assert_eq!(a.coverage_iou, 1.0);
        assert_eq!(a.same_voxel_rate, 1.0);
        assert_eq!(a.depth_error_voxels.max, 0.0);
        assert_eq!(a.normal_error_deg.max, 0.0);
    }

    #[test]
    fn coverage_voxels_depth_and_normals_are_measured() {
        let z = [0.0f32, 0.0, 1.0];
        let x = [1.0f32, 0.0, 0.0];
        let r = image(vec![
            Some(hit(0, [0, 0, 0], 1.0, z)),
            Some(hit(0, [1, 0, 0], 1.0, z)),
            Some(hit(1, [0, 0, 0], 1.0, z)),
            Some(hit(1, [0, 0, 0], 1.0, z)),
            None,
        ]);
        let g = vec![
            // Same voxel, 0.25 world units off: 0.5 cells of instance 0.
            gpu(0, [0, 0, 0], 1.25, z),
            // Other cell, normal 90° off.
            gpu(0, [2, 0, 0], 1.0, x),
            // Same cell but another instance: not the same voxel; 2 cells of instance 1.
            gpu(0, [0, 0, 0], 3.0, z),
            // Missed.
            None,
            // Extra.
            gpu(0, [0, 0, 0], 1.0, z),
        ];
        let a = compare(&r, &g, &[0.5, 1.0]).unwrap();
        assert_eq!(
            (a.covered_reference, a.covered_gpu, a.covered_both),
            (4, 4, 3)
        );
        assert!((a.coverage_iou - 3.0 / 5.0).abs() < 1e-12);
        assert!((a.same_voxel_rate - 1.0 / 3.0).abs() < 1e-12);
        let d = a.depth_error_voxels;
        assert_eq!(d.count, 3);
        assert_eq!((d.median, d.p95, d.max), (0.5, 2.0, 2.0));
        let n = a.normal_error_deg;
        assert_eq!((n.median, n.max), (0.0, 90.0));
        // Serializes (the bench writes JSON).
        let json = serde_json::to_string(&a).unwrap();
        assert!(json.contains("\"same_voxel_rate\""));
    }

    #[test]
    fn empty_images_and_bad_inputs() {
        let a = compare(&image(vec![None; 3]), &[None, None, None], &[]).unwrap();
        assert_eq!(a.coverage_iou, 1.0);
        assert_eq!(a.same_voxel_rate, 1.0);
        assert_eq!(a.depth_error_voxels, ErrorStats::default());
        let z = [0.0f32, 0.0, 1.0];
        let r = image(vec![Some(hit(2, [0; 3], 1.0, z))]);
        assert_eq!(
            compare(&r, &[gpu(2, [0; 3], 1.0, z)], &[1.0]),
            Err(AccuracyError::MissingCellSize(2))
        );
        assert!(matches!(
            compare(&r, &[None, None], &[1.0]),
            Err(AccuracyError::SizeMismatch { .. })
        ));
        assert!(matches!(
            compare(&r, &[None], &[0.0]),
            Err(AccuracyError::BadCellSize { .. })
        ));
    }

    #[test]
    fn degenerate_normals_count_as_opposite() {
        assert_eq!(angle_deg([0.0; 3], [0.0, 0.0, 1.0]), 180.0);
        assert_eq!(angle_deg([0.0, 0.0, 1.0], [0.0; 3]), 180.0);
        assert_eq!(angle_deg([0.0, 1.0, 0.0], [f32::INFINITY, 0.0, 0.0]), 180.0);
        assert_eq!(angle_deg([f32::NAN, 0.0, 0.0], [0.0, 0.0, 1.0]), 180.0);
        assert!((angle_deg([0.0, 0.0, 2.0], [0.0, 0.0, -1.0]) - 180.0).abs() < 1e-9);
        assert!((angle_deg([1.0, 1.0, 0.0], [1.0, 0.0, 0.0]) - 45.0).abs() < 1e-9);
        // Every component of both vectors counts (the length of each, not only the dot).
        let diagonal = (1.0f64 / 3.0f64.sqrt()).acos().to_degrees();
        for (a, b) in [
            ([1.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
            ([1.0, 1.0, 1.0], [0.0, 1.0, 0.0]),
            ([0.0, 0.0, 3.0], [2.0, 2.0, 2.0]),
        ] {
            assert!((angle_deg(a, b) - diagonal).abs() < 1e-9, "{a:?} {b:?}");
        }
    }

    #[test]
    fn percentiles_use_nearest_rank() {
        let s = ErrorStats::of((1..=100).map(f64::from).collect());
        assert_eq!((s.count, s.median, s.p95, s.max), (100, 50.0, 95.0, 100.0));
        let s = ErrorStats::of(vec![3.0]);
        assert_eq!((s.median, s.p95, s.max), (3.0, 3.0, 3.0));
    }

    #[test]
    fn psnr_of_rgba8_images() {
        let a = [10u8, 20, 30, 255, 0, 0, 0, 0];
        assert_eq!(psnr_rgba8(&a, &a), Some(f64::INFINITY));
        // Alpha is ignored.
        let mut b = a;
        b[3] = 0;
        assert_eq!(psnr_rgba8(&a, &b), Some(f64::INFINITY));
        // One channel off by 255 of 6: MSE = 255² / 6 → 10·log10(6).
        let mut c = a;
        c[4] = 255;
        let p = psnr_rgba8(&a, &c).unwrap();
        assert!((p - 10.0 * 6f64.log10()).abs() < 1e-12);
        assert_eq!(psnr_rgba8(&a, &a[..4]), None);
        assert_eq!(psnr_rgba8(&a[..3], &a[..3]), None);
    }
}
