//! `ssbvb-passes`: the render-graph passes and what runs them.
//!
//! - [`kinds`]: one module and one WGSL file (under `shaders/`, same name) per pass kind,
//!   registered by one line each;
//! - [`runtime`]: the frame executor ([`Renderer`]), the registration table's types, bind
//!   groups from declared slots, pipeline building, adapter needs, counters, embedding;
//! - [`measure`]: reading a frame back for the accuracy measures and the lighting
//!   reference.
//!
//! The scene on the GPU and the compute building blocks are `ssbvb-gpu`'s; the GPU build
//! steps (voxelization, LOD build, surface build, splicing) are `ssbvb-gpu-build`'s.
//!
//! Bindings: group 0 is the scene (frame constants, visible instances, every LOD's point
//! cloud, page tables, page pools, coarse occupancy and the hierarchy over the visible
//! instances' boxes; `shaders/common.inc.wgsl`); group 1 holds the pass's graph resources
//! and its own resources, laid out from the pass's declaration ([`runtime::bindings`]).

pub mod error;
pub mod kinds;
pub mod measure;
pub mod runtime;

pub use error::PassError;
pub use kinds::{REGISTRY, create_pass, registered_kinds, registration};
pub use runtime::adapter_needs::{pipeline_requirements, pipeline_requirements_for};
pub use runtime::counters::FrameCounters;
pub use runtime::node::{CounterSource, PassNode};
pub use runtime::recorder::Recorder;
pub use runtime::registry::{PassImpl, PassInit, Registration};
pub use runtime::renderer::{FrameStats, PassTimesReadout, PassTiming, Profiling, Renderer};
pub use runtime::resources::PHYSICAL_LABEL_MARK;
