//! What a render draws, on the CPU: a scene with its camera, pipeline, budget and the notes
//! and warnings of its preparation. Made from a scene file, a model file at a level, a
//! prepared asset, a [`Scene`] built in code, or voxel arrays ([`crate::arrays`]).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::progress::Progress;

use crate::budget::PageSourceRef;
use crate::{EngineError, Warning};

/// The level a model file is voxelized at when none is given.
pub const DEFAULT_MODEL_LEVEL: u32 = 8;

/// A scene ready to upload, with what its preparation said.
#[derive(Clone, Default)]
pub struct Content {
    /// What to draw.
    pub scene: Scene,
    /// The scene's camera (for a model: [`Content::default_camera`]).
    pub camera: Camera,
    /// The pipeline file the scene names (`None`: the adapter's default form).
    pub pipeline: Option<PathBuf>,
    /// One line per asset about the cache (hit, or rebuilt and why).
    pub notes: Vec<String>,
    /// What was used instead of what the files asked for (a missing texture, …).
    pub warnings: Vec<Warning>,
    /// The scene's GPU budget (MiB), if it sets one.
    pub gpu_budget_mib: Option<u64>,
    /// Per object, the cache file its pages stream from under a budget.
    pub page_sources: Vec<Option<PageSourceRef>>,
    /// The scene's animated objects (their assets are their rest pose).
    pub animated: Vec<ssbvb_gpu_build::animated::AnimatedMesh>,
}

impl Content {
    /// Opens a scene file (`.ron`), or prepares a model file (OBJ, PLY, glTF/GLB, VOX, raw
    /// grid) or reads a prepared asset (`.ssbvb`) at `level` (default: 8 for a model, an
    /// asset's finest level), placed at the origin and drawn at that level. Models go
    /// through the asset cache.
    pub fn open(
        input: &Path,
        level: Option<u32>,
        progress: &dyn Progress,
    ) -> Result<Self, EngineError> {
        let is_scene = input
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ron"));
        if is_scene {
            if level.is_some() {
                return Err(EngineError::Invalid(
                    "--level applies to a model file; a scene names each object's level".into(),
                ));
            }
            return crate::scene_file::load(input, progress);
        }
        // A prepared asset file (a viewer's save) is drawn at its finest level by default.
        let saved = ssbvb_voxel::cache::asset_file_header(input)
            .map_err(|e| EngineError::Invalid(format!("reading the model: {e}")))?;
        let level = level.unwrap_or(saved.map_or(DEFAULT_MODEL_LEVEL, |h| h.level));
        let (asset, outcome) = ssbvb_voxel::cache::load_or_prepare(input, level, None, progress)
            .map_err(|e| EngineError::from(e).context(format!("preparing {}", input.display())))?;
        let warnings = outcome
            .warnings
            .iter()
            .map(|w| Warning::from_loader(w, &input.display().to_string()))
            .collect();
        let mut content = Self::of_asset(Arc::new(asset), level);
        content.notes = vec![format!("{}: {outcome}", input.display())];
        content.warnings = warnings;
        content.page_sources = vec![PageSourceRef::of(&outcome, level)];
        Ok(content)
    }

    /// One asset at the origin, drawn at `level`, seen by [`Content::default_camera`].
    pub fn of_asset(asset: Arc<VoxelAsset>, level: u32) -> Self {
        Self::of_scene(Scene {
            objects: vec![VoxelObject {
                asset,
                instances: vec![DAffine3::IDENTITY],
                lod: LodPolicy::Fixed(level),
            }],
            ..Default::default()
        })
    }

    /// A scene built in code, seen by [`Content::default_camera`]; no page streams from a
    /// cache file.
    pub fn of_scene(scene: Scene) -> Self {
        let objects = scene.objects.len();
        Self {
            scene,
            camera: Self::default_camera(),
            page_sources: vec![None; objects],
            ..Default::default()
        }
    }

    /// The camera of a model: [`Camera::default`] (the object box seen from +Z) with no far
    /// plane, so a distant view is never clipped away.
    pub fn default_camera() -> Camera {
        Camera {
            far: f64::INFINITY,
            ..Camera::default()
        }
    }

    /// Adds `other`'s objects, volumes, triangles and animated objects, each placed by
    /// `transform` after its own placement, with their notes and warnings. The camera,
    /// light, pipeline and budget stay `self`'s (a program composing content frames it
    /// with [`crate::camera::frame_scene`]).
    pub fn merge(&mut self, other: Content, transform: DAffine3) {
        let first = self.scene.objects.len();
        let Scene {
            objects,
            triangles,
            volumes,
            ..
        } = other.scene;
        self.scene.objects.extend(objects.into_iter().map(|mut o| {
            o.instances.iter_mut().for_each(|i| *i = transform * *i);
            o
        }));
        self.scene
            .triangles
            .extend(triangles.into_iter().map(|mut t| {
                t.transform = transform * t.transform;
                t
            }));
        self.scene.volumes.extend(volumes.into_iter().map(|mut v| {
            v.instances.iter_mut().for_each(|i| *i = transform * *i);
            v
        }));
        self.page_sources.resize(first, None);
        self.page_sources.extend(other.page_sources);
        self.page_sources.resize(self.scene.objects.len(), None);
        self.animated
            .extend(other.animated.into_iter().map(|mut a| {
                a.object += first;
                a
            }));
        self.notes.extend(other.notes);
        self.warnings.extend(other.warnings);
    }

    /// The warnings as lines (`file: what`).
    pub fn warning_lines(&self) -> Vec<String> {
        self.warnings.iter().map(ToString::to_string).collect()
    }
}

/// Why a view may show nothing, from the scene and camera alone: every voxel instance
/// beyond the far plane (the GPU clips there; the reference does not), or none in front of
/// the camera; or objects so far that f32 camera-relative rays lose voxels.
pub fn clipping_warnings(scene: &Scene, camera: &Camera) -> Vec<String> {
    let forward = camera.basis().2;
    let mut spans = Vec::new();
    let mut imprecise = None;
    for o in &scene.objects {
        let finest = o.asset.lods.len().saturating_sub(1) as u32;
        let level = match o.lod {
            LodPolicy::Fixed(l) => l.min(finest),
            LodPolicy::Auto { .. } => finest,
        };
        for xf in &o.instances {
            // Bounding sphere of the object box [-1, 1]^3.
            let radius = (xf.matrix3 * DVec3::ONE)
                .length()
                .max((xf.matrix3 * DVec3::new(1.0, 1.0, -1.0)).length())
                .max((xf.matrix3 * DVec3::new(1.0, -1.0, 1.0)).length())
                .max((xf.matrix3 * DVec3::new(-1.0, 1.0, 1.0)).length());
            let depth = (xf.translation - camera.position).dot(forward);
            spans.push((depth - radius, depth + radius));
            // The GPU works in f32 relative to the camera: about 2^-22 of the distance is
            // lost, which is more than a fraction of a voxel far away.
            let cell = 2.0 * xf.matrix3.determinant().abs().cbrt() / (1u64 << level) as f64;
            let dist = (xf.translation - camera.position).length();
            if dist * 2f64.powi(-22) > cell / 8.0 {
                imprecise.get_or_insert((dist, cell));
            }
        }
    }
    let mut out = Vec::new();
    if let Some((dist, cell)) = imprecise {
        out.push(format!(
            "an object is {dist:.3e} units from the camera with voxels of {cell:.3e}: the GPU's \
             f32 camera-relative rays lose about {:.1e} units there, so voxels may be missing \
             (known limit; `--reference` is exact)",
            dist * 2f64.powi(-22)
        ));
    }
    if spans.is_empty() {
        return out;
    }
    if spans.iter().all(|&(_, far_end)| far_end <= 0.0) {
        out.push("every voxel object is behind the camera: nothing to draw".to_string());
    } else if !camera.is_infinite() && spans.iter().all(|&(near_end, _)| near_end >= camera.far) {
        out.push(format!(
            "every voxel object lies beyond the far plane ({}): the GPU draws nothing; use \
             --far 0 (no far plane) or a larger --far",
            camera.far
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::one_voxel;

    /// Merged content keeps the first's camera and objects, places the second's after
    /// the transform, and keeps one page source per object.
    #[test]
    fn merge_places_the_added_objects_and_keeps_the_first_camera() {
        let asset = one_voxel(1);
        let mut a = Content::of_asset(asset.clone(), 1);
        a.camera = Camera::new(DVec3::new(5.0, 0.0, 0.0), DVec3::ZERO);
        a.page_sources.clear();
        let mut b = Content::of_asset(asset, 1);
        b.scene.objects[0].instances = vec![DAffine3::from_scale(DVec3::splat(2.0))];
        b.warnings.push(Warning::new("b.obj", "missing texture"));
        let shift = DAffine3::from_translation(DVec3::new(0.0, 3.0, 0.0));
        a.merge(b, shift);
        assert_eq!(a.scene.objects.len(), 2);
        assert_eq!(a.page_sources.len(), 2);
        assert_eq!(a.camera.position, DVec3::new(5.0, 0.0, 0.0));
        assert_eq!(a.scene.objects[0].instances, vec![DAffine3::IDENTITY]);
        let placed = a.scene.objects[1].instances[0];
        // The object's own scale first, then the shift.
        assert_eq!(
            placed.transform_point3(DVec3::ONE),
            DVec3::new(2.0, 5.0, 2.0)
        );
        assert_eq!(a.warnings.len(), 1);
    }
}
