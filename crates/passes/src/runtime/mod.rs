//! What runs the passes: the resolved pipeline's resources, the pass table and its
//! registration, bind groups from declared slots, pipeline building, adapter needs, the
//! frame executor, counters and embedding in a caller's frame. Nothing here names a pass
//! kind; the kinds live in [`crate::kinds`].

pub mod adapter_needs;
pub mod bindings;
pub mod counters;
pub mod embed;
pub mod jitter;
pub mod node;
pub mod pipelines;
pub mod recorder;
pub mod registry;
pub mod renderer;
pub mod resources;
