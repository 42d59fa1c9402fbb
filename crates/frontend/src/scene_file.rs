//! Scene files (`assets/scenes/*.ron`): voxel objects, triangle objects, camera, light and
//! pipeline. Paths inside a scene are relative to the scene file.
//!
//! ```ron
//! Scene(
//!   pipeline: "../pipelines/ssbvb.ron",
//!   camera: (position: (1.8, 1.2, 2.6), look_at: (0.0, -0.1, 0.0), fov_y: 45.0),
//!   objects: [
//!     (model: "../models/bunny.obj", level: 8, lod: Fixed(8),
//!      instances: [(translation: (0.0, 0.0, 0.0), rotation_y_deg: 0.0, scale: 1.0)]),
//!   ],
//!   triangles: [Plane(center: (0.0, -1.0, 0.0), half_size: 3.0, color: (0.55, 0.6, 0.55, 1.0))],
//! )
//! ```

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use glam::DVec3;
use ssbvb_gpu::scene::{LodPolicy, Scene, TriangleObject, VolumeObject, VoxelObject};
use ssbvb_scene_file::{InstanceDesc, LodDesc, TriangleDesc, VolumeDesc, VolumeSource};
use ssbvb_voxel::camera::Camera;

/// A scene ready to upload, with its camera and pipeline path.
pub struct LoadedScene {
    /// The scene.
    pub scene: Scene,
    /// The camera.
    pub camera: Camera,
    /// The pipeline file the scene names (`None`: the adapter's default SSBVB form,
    /// [`crate::pipeline_choice`]).
    pub pipeline: Option<PathBuf>,
    /// One line per object about its asset cache (hit or rebuilt and why).
    pub notes: Vec<String>,
    /// The scene's GPU budget (MiB), if it sets one.
    pub gpu_budget_mib: Option<u64>,
    /// Per object, the cache file its pages stream from under a budget.
    pub page_sources: Vec<Option<crate::budget::PageSourceRef>>,
    /// The animated objects (their assets are their rest pose, prepared on the CPU).
    pub animated: Vec<ssbvb_gpu_build::animated::AnimatedMesh>,
}

/// Reads a scene file and prepares (or loads from cache) every object's asset.
pub fn load(path: &Path, progress: &dyn ssbvb_voxel::progress::Progress) -> Result<LoadedScene> {
    load_with_cache(path, None, progress)
}

/// [`load`] with the asset cache in `cache` (`None`: the default cache folder).
fn load_with_cache(
    path: &Path,
    cache: Option<&Path>,
    progress: &dyn ssbvb_voxel::progress::Progress,
) -> Result<LoadedScene> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read scene {}", path.display()))?;
    let file = ssbvb_scene_file::parse(&text, &path.display().to_string())?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut scene = Scene {
        light: file.light.unwrap_or_default(),
        ..Default::default()
    };
    let mut notes = Vec::new();
    let mut page_sources = Vec::new();
    let mut animated = Vec::new();
    for (oi, o) in file.objects.iter().enumerate() {
        let model = dir.join(&o.model);
        let what = || format!("scene {}: object {}", path.display(), o.model);
        let asset = if let Some(animation) = o.animate {
            // Animated: the mesh itself, voxelized in the space of its whole motion.
            let ssbvb_voxel::model::Model::Mesh(mesh) =
                ssbvb_voxel::load::load_model(&model).with_context(what)?
            else {
                bail!("{}: animate needs a mesh model (OBJ, PLY, glTF)", what());
            };
            let anim = ssbvb_gpu_build::animated::AnimatedMesh::new(oi, mesh, animation, o.level)
                .with_context(what)?;
            let rest = anim.cpu_asset(0.0).with_context(what)?;
            notes.push(format!(
                "{}: animated, re-voxelized on the GPU each frame",
                o.model
            ));
            page_sources.push(None);
            animated.push(anim);
            rest
        } else {
            let (asset, outcome) =
                ssbvb_voxel::cache::load_or_prepare(&model, o.level, cache, progress)
                    .with_context(what)?;
            notes.push(format!("{}: {outcome}", o.model));
            match o.edits.as_deref() {
                Some(edits) if !edits.is_empty() => {
                    let (asset, r) = edited(&asset, o.level, edits).with_context(what)?;
                    notes.push(format!(
                        "{}: {} edits: {} voxels added, {} removed, {} brush cells outside \
                         the grid left out",
                        o.model,
                        edits.len(),
                        r.added,
                        r.removed,
                        r.clipped
                    ));
                    // Edited voxels are not the cache file's: nothing to page from it.
                    page_sources.push(None);
                    asset
                }
                _ => {
                    page_sources.push(crate::budget::PageSourceRef::of(&outcome, o.level));
                    asset
                }
            }
        };
        let lod = match o.lod {
            None => LodPolicy::Fixed(o.level),
            Some(LodDesc::Fixed(l)) => LodPolicy::Fixed(l),
            Some(LodDesc::Auto { bias, pixel_error }) => LodPolicy::Auto { bias, pixel_error },
        };
        let instances = o.instances.clone().unwrap_or_else(|| {
            vec![InstanceDesc {
                translation: (0.0, 0.0, 0.0),
                rotation_y_deg: 0.0,
                scale: 1.0,
            }]
        });
        scene.objects.push(VoxelObject {
            asset: Arc::new(asset),
            instances: instances.iter().map(InstanceDesc::transform).collect(),
            lod,
        });
    }
    for (i, v) in file.volumes.iter().enumerate() {
        scene.volumes.push(
            volume_object(dir, v, i)
                .with_context(|| format!("scene {}: volumes[{i}]", path.display()))?,
        );
    }
    for t in &file.triangles {
        match *t {
            TriangleDesc::Plane {
                center,
                half_size,
                color,
            } => scene.triangles.push(TriangleObject::ground_plane(
                DVec3::new(center.0, center.1, center.2),
                half_size,
                [color.0, color.1, color.2, color.3],
            )),
        }
    }
    Ok(LoadedScene {
        scene,
        camera: file.camera.camera(),
        pipeline: file.pipeline.as_ref().map(|p| dir.join(p)),
        notes,
        gpu_budget_mib: file.gpu_budget_mib,
        page_sources,
        animated,
    })
}

/// `asset` with `edits` applied to its level `level` and the coarser levels rebuilt.
fn edited(
    asset: &ssbvb_voxel::asset::VoxelAsset,
    level: u32,
    edits: &[ssbvb_voxel::edit::Edit],
) -> Result<(
    ssbvb_voxel::asset::VoxelAsset,
    ssbvb_voxel::edit::EditReport,
)> {
    let finest = ssbvb_voxel::edit::level_voxels(&asset.lods[level as usize]);
    let (voxels, report) = ssbvb_voxel::edit::apply_edits(&finest, edits)?;
    if voxels.is_empty() {
        bail!("the edits remove every voxel");
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DAffine3;
    use ssbvb_scene_file::MAX_INSTANCES;
    use ssbvb_voxel::progress::NoProgress;

    /// Writes `text` as a scene beside a tiny OBJ (`tri.obj`) and loads it.
    pub(super) fn load_text(text: &str) -> Result<LoadedScene> {
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
    use super::LoadedScene;
    use super::tests::{err, load_text};

    #[test]
    fn edits_change_the_finest_level_and_are_reported() {
        let plain = load_text("Scene(objects: [(model: \"tri.obj\", level: 4)])").unwrap();
        let n = |s: &LoadedScene| s.scene.objects[0].asset.lods[4].point_cloud.voxels.len();
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

/// Builds volume `i` of a scene in `dir`: a procedural cloud, a mesh voxelized with
/// fractional coverage, or a VOX model with palette alpha.
fn volume_object(dir: &Path, v: &VolumeDesc, i: usize) -> Result<VolumeObject> {
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
                cloud.volume(v.edge)?,
            )
        }
        VolumeSource::Model(file) => {
            let model_path = dir.join(file);
            let volume = match ssbvb_voxel::load::load_model(&model_path)? {
                ssbvb_voxel::model::Model::Mesh(mesh) => {
                    if v.edge > ssbvb_scene_file::volumes::MAX_MESH_VOLUME_EDGE {
                        bail!(
                            "{}: a mesh volume is at most {} texels per edge, got {}",
                            model_path.display(),
                            ssbvb_scene_file::volumes::MAX_MESH_VOLUME_EDGE,
                            v.edge
                        );
                    }
                    from_mesh_coverage(&mesh, v.edge.trailing_zeros())?
                }
                ssbvb_voxel::model::Model::Voxels(vm) => from_voxel_model(&vm, v.edge)?,
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

/// The web page (`ssbvb-web`) builds its scenes from fetched bytes with its own code; it
/// must draw what the CLI draws: the same objects (instances, LOD policy, the finest
/// level's voxels), triangles, light and camera.
#[cfg(test)]
mod web_page_tests {
    use ssbvb_voxel::progress::NoProgress;

    #[test]
    fn the_page_builds_the_scenes_the_cli_loads() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        let cache = tempfile::tempdir().unwrap();
        for stem in ["default", "bunnies_64"] {
            let path = root.join(format!("scenes/{stem}.ron"));
            let cli = super::load_with_cache(&path, Some(cache.path()), &NoProgress).unwrap();
            let text = std::fs::read_to_string(&path).unwrap();
            let parsed = ssbvb_web::scene_build::parse_scene(&text, stem).unwrap();
            let assets = parsed
                .models()
                .iter()
                .map(|(model, level)| {
                    let bytes = std::fs::read(path.parent().unwrap().join(model)).unwrap();
                    std::sync::Arc::new(
                        ssbvb_web::scene_build::prepare_model(&bytes, model, *level).unwrap(),
                    )
                })
                .collect();
            let page = parsed.build(assets);
            assert_eq!(page.objects.len(), cli.scene.objects.len(), "{stem}");
            for (p, c) in page.objects.iter().zip(&cli.scene.objects) {
                assert_eq!(p.instances, c.instances, "{stem}");
                assert_eq!(p.lod, c.lod, "{stem}");
                assert_eq!(p.asset.lods.len(), c.asset.lods.len(), "{stem}");
                let finest = |o: &ssbvb_gpu::scene::VoxelObject| {
                    o.asset.lods.last().unwrap().point_cloud.clone()
                };
                assert!(
                    finest(p) == finest(c),
                    "{stem}: the finest level's voxels differ"
                );
            }
            assert_eq!(
                format!("{:?}", page.triangles),
                format!("{:?}", cli.scene.triangles),
                "{stem}"
            );
            assert_eq!(page.light, cli.scene.light, "{stem}");
            assert_eq!(parsed.camera(), cli.camera, "{stem}");
        }
    }
}
