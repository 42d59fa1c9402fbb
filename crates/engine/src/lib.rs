//! # ssbvb-engine
//!
//! The one way to render ssbvb content. Open content (a scene file, a model file at a
//! level, a prepared asset, a [`Scene`](ssbvb_gpu::scene::Scene) built in code, or voxels
//! given as arrays), let the engine choose the pipeline form for the adapter (or name
//! one), render, and read the pixels back. The `ssbvb` command line, its viewer, the web
//! page and the bench are built on this crate.
//!
//! A complete program that renders a scene file to a PNG:
//!
//! ```no_run
//! use std::path::Path;
//!
//! use ssbvb_engine::{Content, Engine, RenderOptions};
//! use ssbvb_voxel::progress::NoProgress;
//!
//! fn main() -> Result<(), Box<dyn std::error::Error>> {
//!     let scene = Path::new("assets/scenes/default.ron");
//!     // The scene's models are voxelized (or read from the asset cache).
//!     let content = Content::open(scene, None, &NoProgress)?;
//!     let options = RenderOptions {
//!         size: (640, 480),
//!         ..RenderOptions::default()
//!     };
//!     // The device, the pipeline form chosen for it, the scene uploaded.
//!     let mut engine = Engine::open(content, &options)?;
//!     for w in engine.warnings() {
//!         eprintln!("warning: {w}");
//!     }
//!     let frame = engine.render()?;
//!     println!(
//!         "{} on {}: {:.1} ms",
//!         engine.choice().pipeline,
//!         engine.adapter(),
//!         frame.frame_wall_ms
//!     );
//!     engine.save_png(Path::new("render.png"))?;
//!     Ok(())
//! }
//! ```
//!
//! Voxels from arrays take the same path: [`Content::from_arrays`] with a dense grid, an
//! occupancy grid or sparse coordinates ([`arrays`]), and [`camera`] frames them.
//!
//! Errors are [`EngineError`] values and nothing panics on bad input; what the engine did
//! instead of what was asked (a missing texture, a budget lowered) comes back as
//! [`Warning`] values ([`Content::warnings`], [`Engine::warnings`]), never only logged.

pub mod animation;
pub mod arrays;
pub mod assets;
pub mod budget;
pub mod calibration;
pub mod camera;
pub mod choice;
mod content;
mod engine;
mod error;
pub mod faults;
pub mod forms;
pub mod platform;
pub mod scene_file;
pub mod session;
pub mod sources;
pub mod timing;
pub mod upload;
pub mod values;
mod warning;

#[cfg(test)]
mod test_support;

pub use content::{Content, DEFAULT_MODEL_LEVEL, clipping_warnings};
pub use engine::{Engine, FrameReport, RenderOptions};
pub use error::{EngineError, ResultExt};
pub use forms::{FORMS, Form, PipelineChoice};
pub use session::HostDevice;
pub use warning::Warning;
