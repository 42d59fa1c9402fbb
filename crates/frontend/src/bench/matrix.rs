//! What each preset measures: the models, levels, image sizes, frame counts and camera
//! of the main matrix (with `--levels`, `--sizes` and `--frames` applied), and the knob
//! values of the sweeps. Changing what a preset covers happens here only.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context, Result};
use glam::DVec3;
use ssbvb_voxel::camera::Camera;

use super::sweep::SweepConfig;
use super::{BenchArgs, Preset};
use crate::render_cmd::assets_dir;

/// A benchmarked model.
#[derive(Debug, Clone)]
pub(super) enum BenchModel {
    /// A model file, voxelized (and cached) per level.
    File(PathBuf),
    /// A procedural voxel set.
    Procedural(&'static str, ssbvb_voxel::procedural::ProceduralModel),
}

impl BenchModel {
    /// Name in reports (the file name, or the procedural model's name).
    pub(super) fn name(&self) -> String {
        match self {
            BenchModel::File(p) => p
                .file_name()
                .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into()),
            BenchModel::Procedural(n, _) => (*n).to_string(),
        }
    }

    /// The voxel asset for `level` (voxelized and cached, or generated); it may lack that
    /// level, which the caller checks.
    pub(super) fn asset(&self, level: u32) -> Result<Arc<ssbvb_voxel::asset::VoxelAsset>> {
        let asset = match self {
            BenchModel::File(path) => {
                ssbvb_voxel::cache::load_or_prepare(
                    path,
                    level,
                    None,
                    &ssbvb_voxel::progress::NoProgress,
                )
                .with_context(|| format!("preparing {}", path.display()))?
                .0
            }
            BenchModel::Procedural(name, m) => {
                let set = m
                    .voxels(level)
                    .with_context(|| format!("generating {name} at level {level}"))?;
                ssbvb_voxel::prepare::prepare_voxel_set(set, &ssbvb_voxel::progress::NoProgress).0
            }
        };
        Ok(Arc::new(asset))
    }
}

/// The matrix a preset runs.
pub(super) struct Matrix {
    /// Models, in report order.
    pub(super) models: Vec<BenchModel>,
    /// Levels (2^level cells per axis).
    pub(super) levels: Vec<u32>,
    /// Image sizes.
    pub(super) sizes: Vec<(u32, u32)>,
    /// Untimed frames per cell.
    pub(super) warmup: usize,
    /// Timed frames per cell.
    pub(super) frames: usize,
    /// The camera of every cell.
    pub(super) camera: Camera,
}

/// The preset's matrix with the command line's overrides.
pub(super) fn matrix(args: &BenchArgs) -> Matrix {
    let bunny = BenchModel::File(assets_dir().join("models/bunny.obj"));
    let mut m = match args.preset {
        Preset::Quick
        | Preset::Scale
        | Preset::Memory
        | Preset::Rastavox
        | Preset::Dynamic
        | Preset::Vct
        | Preset::Volumes => Matrix {
            models: vec![bunny],
            levels: vec![5, 6],
            sizes: vec![(160, 120)],
            warmup: 1,
            frames: 3,
            camera: Camera::new(DVec3::new(0.0, 0.3, 2.6), DVec3::ZERO),
        },
        Preset::Full => Matrix {
            models: vec![bunny],
            levels: vec![7, 8, 9, 10, 11, 12],
            sizes: vec![(640, 480), (1280, 720)],
            warmup: 3,
            frames: 10,
            camera: Camera::new(DVec3::new(0.0, 0.3, 2.6), DVec3::ZERO),
        },
        Preset::Study => Matrix {
            models: vec![
                BenchModel::Procedural(
                    "ball",
                    ssbvb_voxel::procedural::ProceduralModel::FilledBall,
                ),
                BenchModel::Procedural(
                    "random50",
                    ssbvb_voxel::procedural::ProceduralModel::Random {
                        fraction: 0.5,
                        seed: 2,
                    },
                ),
                bunny,
            ],
            levels: (3..=9).collect(),
            sizes: vec![
                (640, 480),
                (800, 600),
                (1280, 720),
                (1366, 768),
                (1600, 1024),
                (1920, 1200),
                (2560, 1440),
            ],
            warmup: 1,
            frames: 5,
            // The grid's cube seen from above a corner, filling most of the view's height.
            camera: Camera::new(DVec3::new(2.2, 1.7, 2.9), DVec3::ZERO),
        },
    };
    if let Some(l) = &args.levels {
        m.levels = l.clone();
    }
    if let Some(s) = &args.sizes {
        m.sizes = s.clone();
    }
    if let Some(f) = args.frames {
        m.frames = f.max(1);
    }
    m
}

/// Sweep sizes of a preset.
pub(super) fn sweep_config(preset: Preset) -> SweepConfig {
    match preset {
        Preset::Quick
        | Preset::Study
        | Preset::Scale
        | Preset::Memory
        | Preset::Rastavox
        | Preset::Dynamic
        | Preset::Vct
        | Preset::Volumes => SweepConfig {
            size: (160, 120),
            level: 6,
            warmup: 1,
            frames: 2,
            max_steps: &[8, 32, 1024],
            size_scale: &[0.9, 1.0, 1.3],
            max_i: &[0.0, 1.0, 3.0],
            min_dist: &[0.0, 0.5, 2.0],
            resolution_scale: &[0.5, 1.0],
            lod_bias: &[-2, -1, 0],
        },
        Preset::Full => SweepConfig {
            size: (640, 480),
            level: 9,
            warmup: 3,
            frames: 10,
            max_steps: &[4, 8, 16, 32, 64, 1024],
            size_scale: &[0.8, 0.9, 1.0, 1.1, 1.3],
            max_i: &[0.0, 1.0, 2.0, 3.0],
            min_dist: &[0.0, 0.25, 0.5, 1.0, 2.0, 4.0],
            resolution_scale: &[0.25, 0.5, 0.75, 1.0],
            lod_bias: &[-3, -2, -1, 0],
        },
    }
}
