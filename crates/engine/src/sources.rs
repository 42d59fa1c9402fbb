//! Where a scene's models come from ([`ModelSource`]): the file system beside the scene
//! with the asset cache ([`Files`]), bytes held in memory ([`ModelBytes`], prepared here
//! with [`prepare_bytes`]), or assets prepared elsewhere ([`Prepared`], the web page's
//! worker). [`crate::scene_file`] builds every scene through one of them.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::model::Model;
use ssbvb_voxel::progress::Progress;

use crate::budget::PageSourceRef;
use crate::{EngineError, Warning};

/// A model prepared at a level for a scene object.
pub struct PreparedModel {
    /// The asset.
    pub asset: Arc<VoxelAsset>,
    /// One line about where it came from (cache hit, rebuilt and why); `None`: say nothing.
    pub note: Option<String>,
    /// The cache file its pages can stream from under a budget.
    pub page_source: Option<PageSourceRef>,
    /// What its loader could not do (a missing material or texture), naming the file.
    pub warnings: Vec<Warning>,
}

/// A model loaded but not prepared, with its load's warnings.
pub struct LoadedModel {
    /// The model.
    pub model: Model,
    /// What its load could not do (a missing material or texture), naming the file.
    pub warnings: Vec<Warning>,
}

/// Where a scene's models come from.
pub trait ModelSource {
    /// The model the scene names `model` prepared at `level`.
    fn prepare(
        &self,
        model: &str,
        level: u32,
        progress: &dyn Progress,
    ) -> Result<PreparedModel, EngineError>;

    /// The model the scene names `model`, loaded but not prepared (animated objects and
    /// volumes made from a model), with what its load could not do.
    fn load(&self, model: &str) -> Result<LoadedModel, EngineError>;

    /// The path a pipeline named by the scene has (`None` where the source has no files).
    fn path_of(&self, relative: &str) -> Option<PathBuf>;
}

/// Models read from the file system beside the scene file, prepared through the asset
/// cache (`cache`: its folder; `None`, the default one).
pub struct Files {
    /// The scene file's folder.
    pub dir: PathBuf,
    /// The asset cache's folder (`None`: [`ssbvb_voxel::cache::default_cache_dir`]).
    pub cache: Option<PathBuf>,
}

impl ModelSource for Files {
    fn prepare(
        &self,
        model: &str,
        level: u32,
        progress: &dyn Progress,
    ) -> Result<PreparedModel, EngineError> {
        let path = self.dir.join(model);
        let (asset, outcome) =
            ssbvb_voxel::cache::load_or_prepare(&path, level, self.cache.as_deref(), progress)?;
        Ok(PreparedModel {
            asset: Arc::new(asset),
            note: Some(format!("{model}: {outcome}")),
            page_source: PageSourceRef::of(&outcome, level),
            warnings: outcome
                .warnings
                .iter()
                .map(|w| Warning::from_loader(w, &path.display().to_string()))
                .collect(),
        })
    }

    fn load(&self, model: &str) -> Result<LoadedModel, EngineError> {
        let path = self.dir.join(model);
        let loaded = ssbvb_voxel::load::load_model_with(&path, &Default::default())?;
        Ok(LoadedModel {
            warnings: loaded
                .warnings
                .iter()
                .map(|w| Warning::from_loader(w, &path.display().to_string()))
                .collect(),
            model: loaded.model,
        })
    }

    fn path_of(&self, relative: &str) -> Option<PathBuf> {
        Some(self.dir.join(relative))
    }
}

/// Models given as bytes by the name the scene gives them (fetched over a network, held
/// in memory), prepared here with no file involved ([`prepare_bytes`]).
#[derive(Default)]
pub struct ModelBytes {
    /// `(model as the scene names it, its bytes)`.
    pub files: Vec<(String, Vec<u8>)>,
}

impl ModelBytes {
    fn bytes_of(&self, model: &str) -> Result<&[u8], EngineError> {
        self.files
            .iter()
            .find(|(m, _)| m == model)
            .map(|(_, b)| b.as_slice())
            .ok_or_else(|| EngineError::Invalid(format!("no bytes were given for {model}")))
    }
}

impl ModelSource for ModelBytes {
    fn prepare(
        &self,
        model: &str,
        level: u32,
        progress: &dyn Progress,
    ) -> Result<PreparedModel, EngineError> {
        let (asset, warnings) = prepare_bytes(self.bytes_of(model)?, model, level, progress)?;
        Ok(PreparedModel {
            asset: Arc::new(asset),
            note: None,
            page_source: None,
            warnings,
        })
    }

    fn load(&self, model: &str) -> Result<LoadedModel, EngineError> {
        use ssbvb_voxel::load::{Format, LoadOptions};
        let bytes = self.bytes_of(model)?;
        let path = Path::new(model);
        let format = Format::from_path(path)
            .or_else(|| Format::sniff(&bytes[..bytes.len().min(64)]))
            .ok_or_else(|| EngineError::Invalid(format!("{model}: not a model ssbvb reads")))?;
        let loaded =
            ssbvb_voxel::load::load_from_bytes(bytes, format, path, None, &LoadOptions::default())?;
        Ok(LoadedModel {
            warnings: loaded
                .warnings
                .iter()
                .map(|w| Warning::from_loader(w, model))
                .collect(),
            model: loaded.model,
        })
    }

    fn path_of(&self, _: &str) -> Option<PathBuf> {
        None
    }
}

/// Models prepared elsewhere (the web page prepares fetched bytes in a worker), by the
/// name and level the scene gives them.
#[derive(Default)]
pub struct Prepared {
    /// `(model as the scene names it, level)` and its asset.
    pub assets: Vec<((String, u32), Arc<VoxelAsset>)>,
}

impl ModelSource for Prepared {
    fn prepare(
        &self,
        model: &str,
        level: u32,
        _: &dyn Progress,
    ) -> Result<PreparedModel, EngineError> {
        let asset = self
            .assets
            .iter()
            .find(|((m, l), _)| m == model && *l == level)
            .map(|(_, a)| a.clone())
            .ok_or_else(|| {
                EngineError::Invalid(format!("{model} at level {level} was not prepared"))
            })?;
        Ok(PreparedModel {
            asset,
            note: None,
            page_source: None,
            warnings: Vec::new(),
        })
    }

    fn load(&self, model: &str) -> Result<LoadedModel, EngineError> {
        Err(EngineError::Invalid(format!(
            "{model}: only prepared assets were given, not the model itself"
        )))
    }

    fn path_of(&self, _: &str) -> Option<PathBuf> {
        None
    }
}

/// Loads a model from its bytes (`name`'s extension, else its first bytes, say the format)
/// and prepares it at `level`, with no file involved: the asset `ssbvb voxelize` would
/// write to its cache, and what the load could not do (a material or texture the bytes
/// refer to cannot be read from bytes alone).
pub fn prepare_bytes(
    bytes: &[u8],
    name: &str,
    level: u32,
    progress: &dyn Progress,
) -> Result<(VoxelAsset, Vec<Warning>), EngineError> {
    use ssbvb_voxel::load::{Format, LoadOptions};
    let path = Path::new(name);
    let format = Format::from_path(path)
        .or_else(|| Format::sniff(&bytes[..bytes.len().min(64)]))
        .ok_or_else(|| {
            EngineError::Invalid(format!(
                "{name}: not a model ssbvb reads (OBJ, PLY, glTF/GLB, VOX, raw grid)"
            ))
        })?;
    let loaded =
        ssbvb_voxel::load::load_from_bytes(bytes, format, path, None, &LoadOptions::default())?;
    let warnings = loaded
        .warnings
        .iter()
        .map(|w| Warning::from_loader(w, name))
        .collect();
    let (asset, _) =
        ssbvb_voxel::prepare::prepare_asset(&loaded.model, level, progress).map_err(|error| {
            EngineError::Prepare(ssbvb_voxel::cache::PrepareError::Voxelize {
                path: path.to_path_buf(),
                error,
            })
        })?;
    Ok((asset, warnings))
}

/// The same scene from the file system (through the asset cache) and from bytes in
/// memory: the same objects, instances, LOD, finest voxels, triangles, light and camera.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_file::{SceneDescription, load_with_cache};
    use ssbvb_gpu::scene::VoxelObject;
    use ssbvb_voxel::progress::NoProgress;

    /// A volume made from a model keeps that model's load warnings (its missing MTL library).
    #[test]
    fn a_models_load_warnings_reach_the_content_for_volumes_too() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("m.obj"),
            "mtllib gone.mtl\nusemtl red\nv -1 -1 -1\nv 1 -1 0\nv 0 1 1\nf 1 2 3\n",
        )
        .unwrap();
        let scene = dir.path().join("s.ron");
        std::fs::write(
            &scene,
            "Scene(volumes: [(source: Model(\"m.obj\"), edge: 16)])",
        )
        .unwrap();
        let c = load_with_cache(&scene, Some(&dir.path().join("cache")), &NoProgress).unwrap();
        assert_eq!(c.scene.volumes.len(), 1);
        assert!(
            c.warnings
                .iter()
                .any(|w| w.to_string().contains("gone.mtl")),
            "{:?}",
            c.warnings
        );
    }

    #[test]
    fn a_scene_from_bytes_is_the_scene_from_files() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes");
        let cache = tempfile::tempdir().unwrap();
        for stem in ["default", "bunnies_64"] {
            let path = root.join(format!("{stem}.ron"));
            let files = load_with_cache(&path, Some(cache.path()), &NoProgress).unwrap();
            let description = SceneDescription::read(&path).unwrap();
            let bytes = ModelBytes {
                files: description
                    .models()
                    .into_iter()
                    .map(|(m, _)| (m.clone(), std::fs::read(root.join(&m)).unwrap()))
                    .collect(),
            };
            let memory = description.build(&bytes, &NoProgress).unwrap();
            let (a, b) = (&files.scene, &memory.scene);
            assert_eq!(a.objects.len(), b.objects.len(), "{stem}");
            for (p, q) in a.objects.iter().zip(&b.objects) {
                assert_eq!(p.instances, q.instances, "{stem}");
                assert_eq!(p.lod, q.lod, "{stem}");
                let finest = |o: &VoxelObject| o.asset.lods.last().unwrap().point_cloud.clone();
                assert!(finest(p) == finest(q), "{stem}: the finest voxels differ");
            }
            assert_eq!(format!("{:?}", a.triangles), format!("{:?}", b.triangles));
            assert_eq!(a.light, b.light);
            assert_eq!(files.camera, memory.camera);
            // Bytes have no file to page from, and no path for the pipeline.
            assert!(memory.page_sources.iter().all(Option::is_none));
            assert!(files.page_sources.iter().all(Option::is_some));
        }
        let e = SceneDescription::parse("Scene(objects: [(model: \"x.obj\", level: 3)])", "s.ron")
            .unwrap()
            .build(&ModelBytes::default(), &NoProgress)
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("object x.obj: no bytes were given for x.obj"),
            "{e}"
        );
    }
}
