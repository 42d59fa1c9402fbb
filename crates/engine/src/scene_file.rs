//! Scene files (`assets/scenes/*.ron`) made into [`Content`]: voxel objects, triangle
//! objects, volumes, camera, light, pipeline and budget. This is the one place a scene
//! file becomes a scene: `ssbvb render`, the viewer, the bench and the web page all build
//! through [`SceneDescription::build`], each with its own [`ModelSource`] (the file system
//! with the asset cache natively; bytes fetched and prepared in the browser). Paths inside
//! a scene are relative to the scene file.
//!
//! ```ron
//! Scene(
//!   pipeline: "../pipelines/ssbvb_unique.ron",
//!   camera: (position: (1.8, 1.2, 2.6), look_at: (0.0, -0.1, 0.0), fov_y: 45.0),
//!   objects: [
//!     (model: "../models/bunny.obj", level: 8, lod: Fixed(8),
//!      instances: [(translation: (0.0, 0.0, 0.0), rotation_y_deg: 0.0, scale: 1.0)]),
//!   ],
//!   triangles: [Plane(center: (0.0, -1.0, 0.0), half_size: 3.0, color: (0.55, 0.6, 0.55, 1.0))],
//! )
//! ```

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use ssbvb_gpu::scene::{LodPolicy, Scene, TriangleObject, VolumeObject, VoxelObject};
use ssbvb_scene_file::{InstanceDesc, LodDesc, SceneFile, TriangleDesc, VolumeDesc, VolumeSource};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::Model;
use ssbvb_voxel::progress::Progress;

use crate::error::ResultExt;
pub use crate::sources::{
    Files, LoadedModel, ModelBytes, ModelSource, Prepared, PreparedModel, prepare_bytes,
};
use crate::{Content, EngineError, Warning};

/// A scene file read and checked, its models not yet loaded.
#[derive(Debug)]
pub struct SceneDescription {
    /// Where it came from, for messages (the file's path or URL).
    pub name: String,
    /// The parsed file.
    pub file: SceneFile,
}

impl SceneDescription {
    /// Parses a scene file's text; `name` names it in errors (with line and column).
    pub fn parse(text: &str, name: &str) -> Result<Self, EngineError> {
        Ok(Self {
            name: name.to_string(),
            file: ssbvb_scene_file::parse(text, name)?,
        })
    }

    /// Reads and parses the scene file at `path`.
    pub fn read(path: &Path) -> Result<Self, EngineError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| EngineError::io(path, e).context("cannot read the scene"))?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Each object's model (as the scene names it) and level, in object order.
    pub fn models(&self) -> Vec<(String, u32)> {
        self.file
            .objects
            .iter()
            .map(|o| (o.model.clone(), o.level))
            .collect()
    }

    /// The scene's camera.
    pub fn camera(&self) -> Camera {
        self.file.camera.camera()
    }

    /// The scene with every object's model from `source` (prepared, edited, animated),
    /// its volumes, triangles, light, camera, pipeline and budget.
    pub fn build(
        &self,
        source: &dyn ModelSource,
        progress: &dyn Progress,
    ) -> Result<Content, EngineError> {
        let file = &self.file;
        let mut content = Content {
            scene: Scene {
                light: file.light.unwrap_or_default(),
                ..Default::default()
            },
            camera: file.camera.camera(),
            pipeline: file.pipeline.as_ref().and_then(|p| source.path_of(p)),
            gpu_budget_mib: file.gpu_budget_mib,
            ..Content::default()
        };
        for (oi, o) in file.objects.iter().enumerate() {
            let what = || format!("scene {}: object {}", self.name, o.model);
            let asset = self
                .object_asset(oi, source, progress, &mut content)
                .context_with(what)?;
            let lod = match o.lod {
                None => LodPolicy::Fixed(o.level),
                Some(LodDesc::Fixed(l)) => LodPolicy::Fixed(l),
                Some(LodDesc::Auto { bias, pixel_error }) => LodPolicy::Auto { bias, pixel_error },
            };
            let instances = match &o.instances {
                Some(list) => list.iter().map(InstanceDesc::transform).collect(),
                None => vec![glam::DAffine3::IDENTITY],
            };
            content.scene.objects.push(VoxelObject {
                asset,
                instances,
                lod,
            });
        }
        for (i, v) in file.volumes.iter().enumerate() {
            content.scene.volumes.push(
                volume_object(source, v, i, &mut content.warnings)
                    .context_with(|| format!("scene {}: volumes[{i}]", self.name))?,
            );
        }
        for t in &file.triangles {
            let TriangleDesc::Plane {
                center,
                half_size,
                color,
            } = *t;
            content.scene.triangles.push(TriangleObject::ground_plane(
                DVec3::new(center.0, center.1, center.2),
                half_size,
                [color.0, color.1, color.2, color.3],
            ));
        }
        Ok(content)
    }

    /// Object `oi`'s asset: animated (its rest pose), edited, or as prepared; its note,
    /// page source and warnings go into `content`.
    fn object_asset(
        &self,
        oi: usize,
        source: &dyn ModelSource,
        progress: &dyn Progress,
        content: &mut Content,
    ) -> Result<Arc<VoxelAsset>, EngineError> {
        let o = &self.file.objects[oi];
        if let Some(animation) = o.animate {
            // Animated: the mesh itself, voxelized in the space of its whole motion.
            let loaded = source.load(&o.model)?;
            content.warnings.extend(loaded.warnings);
            let Model::Mesh(mesh) = loaded.model else {
                return Err(EngineError::Invalid(
                    "animate needs a mesh model (OBJ, PLY, glTF)".into(),
                ));
            };
            let anim = ssbvb_gpu_build::animated::AnimatedMesh::new(oi, mesh, animation, o.level)?;
            let rest = anim.cpu_asset(0.0)?;
            content.notes.push(format!(
                "{}: animated, re-voxelized on the GPU each frame",
                o.model
            ));
            content.page_sources.push(None);
            content.animated.push(anim);
            return Ok(Arc::new(rest));
        }
        let prepared = source.prepare(&o.model, o.level, progress)?;
        content.notes.extend(prepared.note);
        content.warnings.extend(prepared.warnings);
        match o.edits.as_deref() {
            Some(edits) if !edits.is_empty() => {
                let (asset, r) = edited(&prepared.asset, o.level, edits)?;
                content.notes.push(format!(
                    "{}: {} edits: {} voxels added, {} removed, {} brush cells outside \
                     the grid left out",
                    o.model,
                    edits.len(),
                    r.added,
                    r.removed,
                    r.clipped
                ));
                // Edited voxels are not the cache file's: nothing to page from it.
                content.page_sources.push(None);
                Ok(Arc::new(asset))
            }
            _ => {
                content.page_sources.push(prepared.page_source);
                Ok(prepared.asset)
            }
        }
    }
}

/// Reads a scene file and prepares (or loads from the default cache) every object's asset.
pub fn load(path: &Path, progress: &dyn Progress) -> Result<Content, EngineError> {
    load_with_cache(path, None, progress)
}

/// [`load`] with the asset cache in `cache` (`None`: the default cache folder).
pub fn load_with_cache(
    path: &Path,
    cache: Option<&Path>,
    progress: &dyn Progress,
) -> Result<Content, EngineError> {
    let description = SceneDescription::read(path)?;
    let files = Files {
        dir: path.parent().unwrap_or(Path::new(".")).to_path_buf(),
        cache: cache.map(Path::to_path_buf),
    };
    description.build(&files, progress)
}

/// `asset` with `edits` applied to its level `level` and the coarser levels rebuilt.
fn edited(
    asset: &VoxelAsset,
    level: u32,
    edits: &[ssbvb_voxel::edit::Edit],
) -> Result<(VoxelAsset, ssbvb_voxel::edit::EditReport), EngineError> {
    let lod = asset.lods.get(level as usize).ok_or_else(|| {
        EngineError::Invalid(format!(
            "edits at level {level}, but the asset holds levels 0..={}",
            asset.lods.len().saturating_sub(1)
        ))
    })?;
    let finest = ssbvb_voxel::edit::level_voxels(lod);
    let (voxels, report) = ssbvb_voxel::edit::apply_edits(&finest, edits)
        .map_err(|e| EngineError::Invalid(e.to_string()))?;
    if voxels.is_empty() {
        return Err(EngineError::Invalid("the edits remove every voxel".into()));
    }
    let set = ssbvb_voxel::voxelize::VoxelSet {
        object_space: asset.object_space,
        voxels,
        report: Default::default(),
    };
    let (asset, _) =
        ssbvb_voxel::prepare::prepare_voxel_set(set, &ssbvb_voxel::progress::NoProgress);
    Ok((asset, report))
}

/// Builds volume `i` of a scene with models from `source`: a procedural cloud, a mesh
/// voxelized with fractional coverage, or a VOX model with palette alpha.
fn volume_object(
    source: &dyn ModelSource,
    v: &VolumeDesc,
    i: usize,
    warnings: &mut Vec<Warning>,
) -> Result<VolumeObject, EngineError> {
    use ssbvb_voxel::rgba_volume::sources::{Cloud, from_mesh_coverage, from_voxel_model};
    let (name, volume) = match &v.source {
        VolumeSource::Cloud {
            seed,
            density,
            colour,
        } => {
            let cloud = Cloud {
                seed: *seed,
                density: *density,
                colour: [colour.0, colour.1, colour.2],
            };
            (
                format!("volumes[{i}] (cloud {seed})"),
                cloud
                    .volume(v.edge)
                    .map_err(|e| EngineError::Invalid(e.to_string()))?,
            )
        }
        VolumeSource::Model(file) => {
            let invalid = |e: &dyn std::fmt::Display| EngineError::Invalid(e.to_string());
            let loaded = source.load(file)?;
            warnings.extend(loaded.warnings);
            let volume = match loaded.model {
                Model::Mesh(mesh) => {
                    if v.edge > ssbvb_scene_file::volumes::MAX_MESH_VOLUME_EDGE {
                        return Err(EngineError::Invalid(format!(
                            "{}: a mesh volume is at most {} texels per edge, got {}",
                            source
                                .path_of(file)
                                .map_or(file.clone(), |p| p.display().to_string()),
                            ssbvb_scene_file::volumes::MAX_MESH_VOLUME_EDGE,
                            v.edge
                        )));
                    }
                    from_mesh_coverage(&mesh, v.edge.trailing_zeros()).map_err(|e| invalid(&e))?
                }
                Model::Voxels(vm) => from_voxel_model(&vm, v.edge).map_err(|e| invalid(&e))?,
            };
            (format!("volumes[{i}] ({file})"), volume)
        }
    };
    Ok(VolumeObject {
        name,
        volume: Arc::new(volume),
        instances: v.placements().iter().map(InstanceDesc::transform).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DAffine3;
    use ssbvb_scene_file::MAX_INSTANCES;
    use ssbvb_voxel::progress::NoProgress;

    /// Writes `text` as a scene beside a tiny OBJ (`tri.obj`) and loads it.
    pub(super) fn load_text(text: &str) -> Result<Content, EngineError> {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("tri.obj"),
            "v -1 -1 -1\nv 1 -1 0\nv 0 1 1\nf 1 2 3\n",
        )
        .unwrap();
        let path = dir.path().join("scene.ron");
        std::fs::write(&path, text).unwrap();
        load_with_cache(&path, Some(&dir.path().join("cache")), &NoProgress)
    }

    pub(super) fn err(text: &str) -> String {
        match load_text(text) {
            Ok(_) => panic!("expected an error for {text}"),
            Err(e) => format!("{e:#}"),
        }
    }

    #[test]
    fn a_small_scene_loads_with_its_defaults() {
        let s = load_text("Scene(objects: [(model: \"tri.obj\", level: 3)])").unwrap();
        assert_eq!(s.scene.objects.len(), 1);
        assert_eq!(s.scene.objects[0].lod, LodPolicy::Fixed(3));
        assert_eq!(s.scene.objects[0].instances, vec![DAffine3::IDENTITY]);
        assert_eq!(s.pipeline, None);
        assert_eq!(s.camera.position, DVec3::new(0.0, 0.0, 3.0));
    }

    #[test]
    fn a_gpu_budget_is_read_with_each_objects_page_source() {
        let s = load_text("Scene(objects: [(model: \"tri.obj\", level: 3)])").unwrap();
        assert_eq!(s.gpu_budget_mib, None);
        let s = load_text("Scene(gpu_budget_mib: 256, objects: [(model: \"tri.obj\", level: 3)])")
            .unwrap();
        assert_eq!(s.gpu_budget_mib, Some(256));
        // The asset was written to the cache: its pages can stream from there.
        assert_eq!(s.page_sources.len(), 1);
        assert!(s.page_sources[0].is_some());
        for bad in ["0", "2000000"] {
            let e = err(&format!(
                "Scene(gpu_budget_mib: {bad}, objects: [(model: \"tri.obj\", level: 3)])"
            ));
            assert!(e.contains("gpu_budget_mib must be 1..="), "{e}");
        }
        let e = err("Scene(gpu_budget_mib: -3, objects: [])");
        assert!(e.contains("scene.ron:1:"), "{e}");
    }

    #[test]
    fn syntax_errors_and_unknown_fields_name_file_line_and_column() {
        let e = err("Scene(\n  objects: [(model: \"tri.obj\", level: 3,)],\n  bogus: 1,\n)");
        assert!(e.contains("scene.ron:3:"), "{e}");
        assert!(e.contains("bogus"), "{e}");
        let e = err("Scene(objects: [(model: \"tri.obj\" level: 3)])");
        assert!(e.contains("scene.ron:1:"), "{e}");
    }

    #[test]
    fn a_missing_model_is_named() {
        let e = err("Scene(objects: [(model: \"nope.obj\", level: 3)])");
        assert!(e.contains("nope.obj"), "{e}");
    }

    #[test]
    fn unusable_values_name_their_field() {
        let cases = [
            (
                "Scene(objects: [(model: \"tri.obj\", level: 3, instances: [(scale: 0.0)])])",
                "objects[0].instances[0].scale must be a positive number, got 0",
            ),
            (
                "Scene(objects: [(model: \"tri.obj\", level: 3, lod: Fixed(5))])",
                "objects[0].lod: Fixed(5) is finer than the object's level 3",
            ),
            (
                "Scene(camera: (position: (0.0, 0.0, 3.0), near: 2.0, far: 1.0))",
                "camera.far (1) must be beyond camera.near (2)",
            ),
            (
                "Scene(camera: (position: (0.0, 0.0, 3.0), near: 1.5, far: 1.5))",
                "camera.far (1.5) must be beyond camera.near (1.5)",
            ),
            (
                "Scene(camera: (position: (0.0, 0.0, 3.0), near: 0.0))",
                "camera.near must be a positive number, got 0",
            ),
            (
                "Scene(camera: (position: (0.0, 0.0, 3.0), fov_y: 180.0))",
                "camera.fov_y must be in (0, 180) degrees, got 180",
            ),
            (
                "Scene(camera: (position: (0.0, 0.0, 0.0)))",
                "camera: position and look_at are the same point",
            ),
            (
                "Scene(triangles: [Plane(center: (0.0, 0.0, 0.0), half_size: -1.0, color: (1.0, 1.0, 1.0, 1.0))])",
                "triangles[0]: half_size must be a positive number",
            ),
        ];
        for (text, want) in cases {
            let e = err(text);
            assert!(e.contains(want), "{text}\n got: {e}");
            assert!(e.contains("scene.ron"), "{e}");
        }
        // A far plane of 0 means none.
        load_text("Scene(camera: (position: (0.0, 0.0, 3.0), far: 0.0))").unwrap();
    }

    #[test]
    fn auto_lod_takes_a_pixel_error_and_refuses_a_bad_one() {
        let s = load_text("Scene(objects: [(model: \"tri.obj\", level: 3, lod: Auto())])").unwrap();
        assert_eq!(s.scene.objects[0].lod, LodPolicy::AUTO);
        let s = load_text(
            "Scene(objects: [(model: \"tri.obj\", level: 3, lod: Auto(pixel_error: 2.5, bias: -1))])",
        )
        .unwrap();
        assert_eq!(
            s.scene.objects[0].lod,
            LodPolicy::Auto {
                bias: -1,
                pixel_error: 2.5
            }
        );
        let e =
            err("Scene(objects: [(model: \"tri.obj\", level: 3, lod: Auto(pixel_error: -1.0))])");
        assert!(
            e.contains("objects[0].lod: Auto pixel_error must be a finite number >= 0, got -1"),
            "{e}"
        );
    }

    /// Millions of instances, or thousands of bad ones, get a short error before anything
    /// is voxelized or uploaded.
    #[test]
    fn too_many_instances_and_many_bad_ones_are_summarized() {
        let many = "(),".repeat(MAX_INSTANCES + 1);
        let e = err(&format!(
            "Scene(objects: [(model: \"tri.obj\", level: 3, instances: [{many}])])"
        ));
        assert!(
            e.contains(&format!("{} instances in all", MAX_INSTANCES + 1)),
            "{e}"
        );
        assert!(e.len() < 400, "{} bytes: {e:.400}", e.len());
        let bad = "(scale: -1.0),".repeat(1000);
        let e = err(&format!(
            "Scene(objects: [(model: \"tri.obj\", level: 3, instances: [{bad}])])"
        ));
        assert!(e.contains("objects[0].instances[7].scale"), "{e}");
        assert!(!e.contains("objects[0].instances[8].scale"), "{e}");
        assert!(e.contains("and 992 more bad instances"), "{e}");
        // The limit itself is allowed.
        let ok = "(),".repeat(MAX_INSTANCES);
        let s = load_text(&format!(
            "Scene(objects: [(model: \"tri.obj\", level: 3, instances: [{ok}])])"
        ))
        .unwrap();
        assert_eq!(s.scene.objects[0].instances.len(), MAX_INSTANCES);
    }
}

#[cfg(test)]
mod edit_tests {
    use super::tests::{err, load_text};
    use crate::Content;

    #[test]
    fn edits_change_the_finest_level_and_are_reported() {
        let plain = load_text("Scene(objects: [(model: \"tri.obj\", level: 4)])").unwrap();
        let n = |s: &Content| s.scene.objects[0].asset.lods[4].point_cloud.voxels.len();
        // A box of 2 × 2 × 2 cells far from the triangle, one cell of it outside the grid.
        let s = load_text(
            "Scene(objects: [(model: \"tri.obj\", level: 4, edits: [\
             AddBox(min: (0.5, -1.0, -1.0), max: (0.74, -0.76, -0.76), color: (1.0, 0.0, 0.0, 1.0)),\
             AddSphere(center: (1.0, 1.0, 1.0), radius: 0.12, color: (0.0, 1.0, 0.0, 1.0))])])",
        )
        .unwrap();
        assert_eq!(n(&s), n(&plain) + 8 + 1);
        assert!(
            s.notes.iter().any(|l| l
                .contains("2 edits: 9 voxels added, 0 removed, 7 brush cells outside the grid")),
            "{:?}",
            s.notes
        );
        assert!(s.page_sources[0].is_none());
        // Removing everything is an error, a bad edit names its place.
        let e = err(
            "Scene(objects: [(model: \"tri.obj\", level: 4, edits: [RemoveBox(min: (-1.0, -1.0, -1.0), max: (1.0, 1.0, 1.0))])])",
        );
        assert!(e.contains("the edits remove every voxel"), "{e}");
        let e = err(
            "Scene(objects: [(model: \"tri.obj\", level: 4, edits: [RemoveSphere(center: (0.0, 0.0, 0.0), radius: -1.0)])])",
        );
        assert!(e.contains("objects[0].edits[0]: a negative radius"), "{e}");
        // Edits of an animated object are refused, not ignored.
        let e = err(
            "Scene(objects: [(model: \"tri.obj\", level: 4, animate: Twist(degrees_per_second: 90.0), edits: [RemoveSphere(center: (0.0, 0.0, 0.0), radius: 0.2)])])",
        );
        assert!(
            e.contains("objects[0]: edits and animate together are not supported yet"),
            "{e}"
        );
    }
}
