//! One file per preset of `ssbvb bench`, each run by `bench::run` alone: `matrix` (the
//! main matrix of `quick`, `full` and `study`) and `sweep` (its knob sweeps), which both
//! feed the main report, and `scale`, `memory`, `rastavox`, `dynamic`, `vct`,
//! `volumes` and `quality`, each writing its own files; `paper` runs `matrix`, `scale` and `figure8` (the
//! paper's Figure 8 scene) and compares their rows with the seed paper's.

pub(super) mod dynamic;
pub(super) mod figure8;
pub(super) mod matrix;
pub(super) mod memory;
pub(super) mod paper;
pub(super) mod quality;
pub(super) mod rastavox;
pub(super) mod scale;
pub(super) mod sweep;
pub(super) mod vct;
pub(super) mod volumes;
