//! The exact CPU reference ray caster: the ground truth every GPU technique is measured
//! against (`docs/architecture.md`, "Accuracy: the CPU reference").
//!
//! For every pixel centre ([`Camera::ray`]) the world ray is taken into each instance's
//! object space in f64 and traced through the instance's sparse lookup with an exact voxel
//! DDA ([`trace_object_ray`]; the hit rules — closed cells, grazing rays hit, tie rule,
//! face normal — are documented in [`dda`]). The nearest hit over all instances wins (on an
//! exact tie the lower instance index); the instances a ray may meet come from an
//! [`InstanceBvh`] over their world boxes, so a pixel costs what its ray meets, not what
//! the scene holds. The hit is shaded with [`shading::shade`] using the
//! voxel's stored normal and colour.
//!
//! Rays start at the eye (`t = 0`), not at the near plane: a camera inside a voxel sees that
//! voxel at `t = 0`. Nothing is clipped at the far plane either.
//!
//! [`dda`]: crate::reference::dda
//! [`shading::shade`]: crate::shading::shade

pub mod dda;
mod supersample;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use glam::{DAffine3, DMat3, DVec3};
use image::ImageEncoder;

pub use self::dda::{
    ObjectHit, TraceCount, Traversal, trace_object_ray, trace_object_ray_counted,
    trace_object_ray_faces,
};
pub use self::supersample::{MAX_SAMPLES, SampleCountError, SampleGrid, render_supersampled};
use crate::asset::LodLevel;
use crate::camera::{Camera, normalize_or};
use crate::instance_bvh::{Aabb, InstanceBvh};
use crate::shading::{Light, linear_to_srgb8, shade};

/// One placed copy of a LOD level.
#[derive(Debug, Clone, Copy)]
pub struct Instance<'a> {
    /// The voxels (lookup + point cloud) of the level to render.
    pub lod: &'a LodLevel,
    /// Object space → world space: `world = object_to_world * object`. Meant to be a
    /// uniform scale, a rotation and a translation; other invertible linear parts work
    /// (normals use the inverse transpose). A singular or non-finite transform hides the
    /// instance.
    pub object_to_world: DAffine3,
    /// Face masks per voxel id of `lod` (a RastaVox level, [`crate::surface::FaceLod`]):
    /// voxels are then hit only through their masked faces ([`trace_object_ray_faces`]).
    pub faces: Option<&'a [u8]>,
}

/// The first voxel a pixel's ray hits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Index of the instance in the slice given to [`render`].
    pub instance: u32,
    /// Voxel id in that instance's LOD point cloud.
    pub voxel: u32,
    /// The voxel's cell in that LOD's grid.
    pub cell: [u32; 3],
    /// World distance from the eye along the (normalized) ray.
    pub t: f64,
    /// Distance along the camera's forward axis (`t · dot(dir, forward)`): the linear depth
    /// a depth buffer stores.
    pub view_depth: f64,
    /// World-space unit normal of the entered voxel face (see [`dda`] for which face;
    /// points against the ray).
    ///
    /// [`dda`]: crate::reference::dda
    pub face_normal: [f32; 3],
    /// World-space hit position (`eye + t · dir`).
    pub position: DVec3,
    /// The eye is inside the voxel (`t == 0`, face normal from the ray's dominant axis).
    pub inside: bool,
}

/// A rendered reference image: per pixel (row-major, row 0 at the top) the hit and the
/// shaded linear colour.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The first voxel hit of each pixel's centre ray, or `None`.
    pub hits: Vec<Option<Hit>>,
    /// Linear RGBA, premultiplied by alpha: with one sample per pixel the shaded colour with
    /// alpha 1 on hits, (0, 0, 0, 0) elsewhere; supersampled, the samples' mean (alpha is
    /// the pixel's coverage).
    pub colors: Vec<[f32; 4]>,
}

/// An instance prepared for tracing: the inverse transform, computed once.
struct Prepared<'a> {
    lod: &'a LodLevel,
    faces: Option<&'a [u8]>,
    /// World → object linear part.
    to_object: DMat3,
    /// Object → world translation (subtracted before `to_object` so that large world
    /// coordinates cancel before they are scaled).
    translation: DVec3,
    /// Object → world normal transform (inverse transpose of the linear part).
    normal_to_world: DMat3,
}

fn prepare<'a>(instances: &[Instance<'a>]) -> Vec<Option<Prepared<'a>>> {
    instances
        .iter()
        .map(|inst| {
            let m = inst.object_to_world;
            let det = m.matrix3.determinant();
            if !(det != 0.0 && det.is_finite() && m.translation.is_finite()) {
                return None;
            }
            let to_object = m.matrix3.inverse();
            if !to_object.is_finite() {
                return None;
            }
            Some(Prepared {
                lod: inst.lod,
                faces: inst.faces,
                to_object,
                translation: m.translation,
                normal_to_world: to_object.transpose(),
            })
        })
        .collect()
}

/// The instances of a render, prepared for tracing, and the hierarchy over their boxes.
struct PreparedScene<'a> {
    instances: Vec<Option<Prepared<'a>>>,
    bvh: InstanceBvh,
}

impl<'a> PreparedScene<'a> {
    fn new(instances: &[Instance<'a>]) -> Self {
        let prepared = prepare(instances);
        let boxes: Vec<Option<Aabb>> = instances
            .iter()
            .zip(&prepared)
            .map(|(inst, p)| {
                p.as_ref()?;
                let b = Aabb::of_instance(&inst.object_to_world)?;
                // The box test runs in world space, the trace in object space: a relative
                // 1e-9 covers the rounding between the two (f64 errors are ~1e-16).
                let size = (b.hi - b.lo).max_element() + b.center().abs().max_element();
                Some(b.widened(size * 1e-9))
            })
            .collect();
        Self {
            instances: prepared,
            bvh: InstanceBvh::build(&boxes),
        }
    }

    /// Traces one world ray (`dir` normalized): the nearest hit, on an exact tie the lower
    /// instance index.
    fn trace(&self, origin: DVec3, dir: DVec3) -> Option<(u32, ObjectHit)> {
        let mut best: Option<(u32, ObjectHit)> = None;
        self.bvh.traverse(origin, dir, |i, _| {
            if let Some(p) = &self.instances[i as usize] {
                // The object-space direction is not renormalized, so the object-space ray
                // parameter *is* the world distance.
                let o = p.to_object * (origin - p.translation);
                let d = p.to_object * dir;
                let hit =
                    trace_object_ray_faces(&p.lod.lookup, p.faces, o, d, Traversal::Hierarchical)
                        .filter(|h| {
                            h.t.is_finite()
                                && best
                                    .as_ref()
                                    .is_none_or(|(bi, b)| h.t < b.t || (h.t == b.t && i < *bi))
                        });
                if let Some(h) = hit {
                    best = Some((i, h));
                }
            }
            best.as_ref().map_or(f64::INFINITY, |(_, b)| b.t)
        });
        best
    }
}

fn to_f32(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// Traces the centre ray of pixel `(px, py)` of a `width × height` image.
pub fn trace_pixel(
    instances: &[Instance],
    camera: &Camera,
    px: u32,
    py: u32,
    width: u32,
    height: u32,
) -> Option<Hit> {
    let scene = PreparedScene::new(instances);
    let rays = camera.pixel_rays(width, height);
    let (o, d) = rays.ray(px, py);
    trace_world(&scene, o, d, rays.forward())
}

/// Traces a world ray: `dir` is normalized here, so [`Hit::t`] is a world distance.
/// `forward` is the camera's forward axis (for [`Hit::view_depth`]).
pub fn trace_ray(instances: &[Instance], origin: DVec3, dir: DVec3, forward: DVec3) -> Option<Hit> {
    let scene = PreparedScene::new(instances);
    trace_world(&scene, origin, normalize_or(dir, forward), forward)
}

fn trace_world(scene: &PreparedScene, origin: DVec3, dir: DVec3, forward: DVec3) -> Option<Hit> {
    let (instance, h) = scene.trace(origin, dir)?;
    let p = scene.instances[instance as usize].as_ref()?;
    let normal = normalize_or(p.normal_to_world * h.face_normal, -dir);
    Some(Hit {
        instance,
        voxel: h.voxel,
        cell: h.cell,
        t: h.t,
        view_depth: h.t * dir.dot(forward),
        face_normal: to_f32(normal),
        position: origin + dir * h.t,
        inside: h.inside,
    })
}

/// The shaded linear RGBA colour of a hit seen along the normalized world direction `dir`
/// (alpha 1): [`shade`] with the voxel's colour and its stored normal taken to world space.
/// A voxel id outside the point cloud (an inconsistent asset) shades mid-grey with the
/// face normal.
pub fn shade_hit(instances: &[Instance], hit: &Hit, dir: DVec3, light: &Light) -> [f32; 4] {
    let Some(inst) = instances.get(hit.instance as usize) else {
        return [0.0; 4];
    };
    let normal_to_world = inst.object_to_world.matrix3.inverse().transpose();
    shade_with(inst.lod, normal_to_world, hit, dir, light)
}

fn shade_with(
    lod: &LodLevel,
    normal_to_world: DMat3,
    hit: &Hit,
    dir: DVec3,
    light: &Light,
) -> [f32; 4] {
    let voxel = lod.point_cloud.voxels.get(hit.voxel as usize);
    debug_assert!(
        voxel.is_some(),
        "voxel id {} outside the point cloud",
        hit.voxel
    );
    let (albedo, normal) = match voxel {
        Some(v) => {
            let c = v.color();
            let n = DVec3::from(v.normal().map(f64::from));
            let face = DVec3::from(hit.face_normal.map(f64::from));
            (
                [c[0], c[1], c[2]],
                to_f32(normalize_or(normal_to_world * n, face)),
            )
        }
        None => ([0.5; 3], hit.face_normal),
    };
    let view = to_f32(-dir);
    let rgb = shade(albedo, normal, view, light);
    let clean = |x: f32| if x.is_finite() { x } else { 0.0 };
    [clean(rgb[0]), clean(rgb[1]), clean(rgb[2]), 1.0]
}

/// A scene prepared once for many rays: the lighting reference ([`crate::lighting`])
/// traces hundreds of rays per pixel through the same instances.
pub struct Tracer<'a> {
    scene: PreparedScene<'a>,
}

impl<'a> Tracer<'a> {
    /// Prepares `instances` (inverse transforms and the hierarchy over their boxes).
    pub fn new(instances: &[Instance<'a>]) -> Self {
        Self {
            scene: PreparedScene::new(instances),
        }
    }

    /// The nearest hit along the world ray from `origin` in direction `dir` (normalized
    /// here; [`Hit::t`] is a world distance, [`Hit::view_depth`] equals it).
    pub fn trace(&self, origin: DVec3, dir: DVec3) -> Option<Hit> {
        let d = normalize_or(dir, DVec3::Z);
        trace_world(&self.scene, origin, d, d)
    }

    /// The linear albedo and the world-space unit stored normal of a hit's voxel (the
    /// inputs of [`shade`]); the face normal and mid-grey for a voxel id outside its point
    /// cloud.
    pub fn surface(&self, hit: &Hit) -> ([f32; 3], [f32; 3]) {
        let placed = self.scene.instances.get(hit.instance as usize);
        let Some(Some(p)) = placed else {
            return ([0.5; 3], hit.face_normal);
        };
        match p.lod.point_cloud.voxels.get(hit.voxel as usize) {
            Some(v) => {
                let c = v.color();
                let n = DVec3::from(v.normal().map(f64::from));
                let face = DVec3::from(hit.face_normal.map(f64::from));
                (
                    [c[0], c[1], c[2]],
                    to_f32(normalize_or(p.normal_to_world * n, face)),
                )
            }
            None => ([0.5; 3], hit.face_normal),
        }
    }
}

/// Renders the reference image: one ray per pixel centre, nearest hit over `instances`,
/// shaded with `light`. Rows are traced in parallel (rayon). With more samples per pixel:
/// [`render_supersampled`].
pub fn render(
    instances: &[Instance],
    camera: &Camera,
    width: u32,
    height: u32,
    light: &Light,
) -> ReferenceImage {
    render_supersampled(instances, camera, width, height, light, SampleGrid::CENTRE)
}

impl ReferenceImage {
    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside the image"
        );
        y as usize * self.width as usize + x as usize
    }

    /// The hit of pixel `(x, y)` (row 0 at the top).
    pub fn hit(&self, x: u32, y: u32) -> Option<&Hit> {
        self.hits[self.index(x, y)].as_ref()
    }

    /// The linear RGBA colour of pixel `(x, y)`.
    pub fn color(&self, x: u32, y: u32) -> [f32; 4] {
        self.colors[self.index(x, y)]
    }

    /// Number of pixels whose ray hits a voxel.
    pub fn coverage(&self) -> usize {
        self.hits.iter().filter(|h| h.is_some()).count()
    }

    /// Whether every number in the image (colours and hit fields) is finite.
    pub fn all_finite(&self) -> bool {
        self.colors.iter().all(|c| c.iter().all(|v| v.is_finite()))
            && self.hits.iter().flatten().all(|h| {
                h.t.is_finite()
                    && h.view_depth.is_finite()
                    && h.position.is_finite()
                    && h.face_normal.iter().all(|v| v.is_finite())
            })
    }

    /// The colours as 8-bit sRGB RGBA with straight alpha (255 on hits, 0 elsewhere; a
    /// supersampled pixel's coverage between).
    pub fn to_rgba8(&self) -> Vec<u8> {
        self.colors
            .iter()
            .flat_map(|c| {
                let alpha = c[3].clamp(0.0, 1.0);
                let a = (alpha * 255.0 + 0.5) as u8;
                // Premultiplied → straight; alpha 1 (every one-sample hit) leaves the colour.
                let straight = |v: f32| if alpha > 0.0 { v / alpha } else { 0.0 };
                [
                    linear_to_srgb8(straight(c[0])),
                    linear_to_srgb8(straight(c[1])),
                    linear_to_srgb8(straight(c[2])),
                    a,
                ]
            })
            .collect()
    }

    /// Face normals as colours (`n · 0.5 + 0.5`, stored as is, no sRGB curve); misses
    /// transparent.
    pub fn normals_rgba8(&self) -> Vec<u8> {
        self.hits
            .iter()
            .flat_map(|h| match h {
                Some(h) => {
                    let c = |v: f32| ((v * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                    [
                        c(h.face_normal[0]),
                        c(h.face_normal[1]),
                        c(h.face_normal[2]),
                        255,
                    ]
                }
                None => [0; 4],
            })
            .collect()
    }

    /// View depth as grey: the nearest hit white, the farthest dark grey (linear in depth
    /// between the image's own min and max); misses transparent.
    pub fn depth_rgba8(&self) -> Vec<u8> {
        let depths = self.hits.iter().flatten().map(|h| h.view_depth);
        let min = depths.clone().fold(f64::INFINITY, f64::min);
        let max = depths.fold(f64::NEG_INFINITY, f64::max);
        let range = max - min;
        self.hits
            .iter()
            .flat_map(|h| match h {
                Some(h) => {
                    let f = if range > 0.0 {
                        (h.view_depth - min) / range
                    } else {
                        0.0
                    };
                    let g = ((1.0 - 0.8 * f).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                    [g, g, g, 255]
                }
                None => [0; 4],
            })
            .collect()
    }

    /// Writes the shaded image as an 8-bit sRGB RGBA PNG (atomically: temp file + rename).
    pub fn to_png(&self, path: impl AsRef<Path>) -> std::io::Result<()> {
        write_png_atomic(path.as_ref(), self.width, self.height, &self.to_rgba8())
    }

    /// Writes [`ReferenceImage::normals_rgba8`] as a PNG (atomically).
    pub fn normals_to_png(&self, path: impl AsRef<Path>) -> std::io::Result<()> {
        write_png_atomic(
            path.as_ref(),
            self.width,
            self.height,
            &self.normals_rgba8(),
        )
    }

    /// Writes [`ReferenceImage::depth_rgba8`] as a PNG (atomically).
    pub fn depth_to_png(&self, path: impl AsRef<Path>) -> std::io::Result<()> {
        write_png_atomic(path.as_ref(), self.width, self.height, &self.depth_rgba8())
    }
}

/// Writes RGBA8 pixels as a PNG: into a temporary file next to `path`, then renamed over
/// it, so a reader never sees a half-written image.
pub fn write_png_atomic(path: &Path, width: u32, height: u32, rgba: &[u8]) -> std::io::Result<()> {
    let name = path.file_name().ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "PNG path has no file name",
        )
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut out = BufWriter::new(File::create(&tmp)?);
        image::codecs::png::PngEncoder::new(&mut out)
            .write_image(rgba, width, height, image::ExtendedColorType::Rgba8)
            .map_err(std::io::Error::other)?;
        out.flush()?;
        out.get_ref().sync_all()?;
        drop(out);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
