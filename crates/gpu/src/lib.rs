//! `ssbvb-gpu`: the GPU resources every other part of ssbvb renders with: the device, the
//! scene on the GPU ([`scene::GpuScene`]: upload, pools, dynamic objects, visibility,
//! streaming, the page cache), the compute building blocks ([`kernels`]: kernel loading,
//! scan, radix sort) and the WGSL sources ([`shaders`]).
//!
//! - [`GpuContext::new_headless`] picks an adapter: a real GPU when there is one, else a
//!   software one (Vulkan lavapipe first, GL llvmpipe as a last resort), overridable with
//!   `SSBVB_ADAPTER` (a name substring, or `software` / `hardware`) and wgpu's own
//!   `WGPU_BACKEND`. It enables timestamp queries and `Depth32FloatStencil8` when the
//!   adapter has them, and asks for the adapter's full limits (the defaults are WebGPU's
//!   minimums). Given the pipeline's [`Requirements`], it skips adapters that lack a
//!   capability the pipeline needs (logging why) and names what is missing when none fits.
//! - Validation errors become Rust errors: [`GpuContext::validated`] wraps work in error
//!   scopes, and errors outside any scope are collected ([`GpuContext::take_uncaptured_errors`])
//!   instead of wgpu's default panic, so tests can fail on them with a message.
//! - [`alloc`]: the large allocations (the scene's streams and pools, the render graph's
//!   resources) in out-of-memory error scopes, so a refused one is
//!   [`GpuError::OutOfMemory`] naming it and its size; and the fault injection that refuses
//!   one.
//! - [`readback`] copies textures (with 256-byte row padding handled) and buffers to the
//!   CPU, and writes PNGs atomically.
//! - [`scene`] uploads a [`scene::Scene`] (objects, instances, LOD policy) and keeps it
//!   current per frame; [`error::ResourceError`] is what building it can fail with.
//! - [`scene_bindings`]: how group 0 binds the scene's streams in as many bindings as their
//!   data needs, and the WGSL generated for that (WebGPU allows 8 storage buffers per
//!   stage).

pub mod alloc;
pub mod buffer_init;
pub mod context;
pub mod error;
pub mod kernels;
pub mod readback;
pub mod requirements;
pub mod scene;
pub mod scene_bindings;
pub mod shader_source;
pub mod shaders;
pub mod submissions;

pub use buffer_init::InitBuffer;
pub use context::*;
pub use error::ResourceError;
pub use requirements::{Requirements, Verdict};
pub use wgpu;
