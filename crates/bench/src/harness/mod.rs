//! What every preset of `ssbvb bench` shares: the bundled pipelines and the pass-kind
//! edits made to them (`pipelines`), the bundled models and the scenes built from them
//! (`models`), timing frames (`frames`), measuring one configuration's frames and its
//! accuracy against the CPU reference (`accuracy`), and the techniques compared
//! (`techniques`). Presets import this module; it imports no preset.

mod accuracy;
pub(crate) mod engine;
mod frames;
mod models;
mod pipelines;
pub(crate) mod techniques;

pub(crate) use accuracy::{
    Measured, Setup, covered_rgba, measure, reference_at, supersampled_reference_at,
};
pub(crate) use frames::{TimedFrames, median, timed_frames};
pub(crate) use models::{
    bench_camera, bundled_asset, bundled_bunny, grid, grid_camera, one_object,
};
pub(crate) use pipelines::{
    bundled_pipeline, technique_pipeline, with_filter_scale, with_kind_edit,
};
