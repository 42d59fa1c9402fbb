//! What the viewer holds: the command line's options, what is loaded before the window
//! exists, and the running viewer's state, in one file so that the app's parts (`open`,
//! `present`, `recover`) and the app itself import it rather than each other.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use ssbvb_gpu::scene::{GpuScene, Scene};
use ssbvb_graph::{PassKind, PipelineWatcher};
use ssbvb_passes::Renderer;
use ssbvb_voxel::camera::Camera;
use winit::window::Window;

use super::super::blit::Blit;
use super::super::camera_control::CameraRig;
use super::super::input::CameraInput;
use super::super::overlay::OverlayState;
use super::super::stats::Stats;
use super::super::surface::WindowGpu;
use ssbvb_engine::faults::Recoveries;

/// Options from the command line.
pub struct Options {
    /// Window title.
    pub title: String,
    /// Initial window size in pixels.
    pub size: (u32, u32),
    /// Exit after this many presented frames.
    pub frames: Option<u64>,
    /// Write a PNG of the last frame here.
    pub screenshot: Option<PathBuf>,
    /// Pipeline files for the technique switch.
    pub techniques: Vec<PathBuf>,
    /// With --frames: write process and device memory at the start and end here.
    pub memory_report: Option<PathBuf>,
    /// Automation: brush steps (paint at a window pixel, undo, redo, save), after the
    /// first frame.
    pub paint: Vec<super::super::script::ScriptStep>,
    /// Where the edited objects are saved when the viewer closes.
    pub save_on_exit: Option<PathBuf>,
    /// Faults injected before given frames (`--inject-fault`, tests).
    pub faults: Vec<ssbvb_engine::faults::Fault>,
    /// Automation: degrees the orbit camera turns every frame after the first.
    pub orbit_deg: Option<f64>,
    /// What the content's preparation and the pipeline's choice said (a missing material
    /// or texture, …): shown in the overlay.
    pub warnings: Vec<String>,
}

/// What is loaded before the window exists.
pub struct Loaded {
    /// The scene (uploaded once the device exists).
    pub scene: Scene,
    /// The scene's camera.
    pub camera: Camera,
    /// The pipeline file, resolved once.
    pub watcher: PipelineWatcher,
    /// Under a GPU budget: how the scene streams (the budget changes live).
    pub streaming: Option<ssbvb_gpu::scene::StreamingOptions>,
    /// Animated objects, re-voxelized on the GPU every frame at the time since start.
    pub animated: Vec<ssbvb_gpu_build::animated::AnimatedMesh>,
    /// With --brush: the editable objects (uploaded with room to change).
    pub brush: Option<super::super::brush::Brush>,
}

/// Whether the loop goes on.
pub(super) enum Flow {
    Continue,
    Exit,
    /// The GPU side must be made again (`recover`).
    Recover(Fault),
}

/// Everything that exists once the window is open.
pub(super) struct Viewer {
    pub(super) window: Arc<Window>,
    /// The event loop's display connection (a new device's surface needs it).
    pub(super) display: winit::event_loop::OwnedDisplayHandle,
    pub(super) gpu: WindowGpu,
    pub(super) blit: Blit,
    pub(super) egui_ctx: egui::Context,
    pub(super) egui_state: egui_winit::State,
    pub(super) egui_renderer: egui_wgpu::Renderer,
    pub(super) scene: GpuScene,
    pub(super) renderer: Renderer,
    /// Animated objects and what updates them (none without animated objects).
    pub(super) animated: Vec<ssbvb_gpu_build::animated::AnimatedMesh>,
    pub(super) animator: Option<ssbvb_gpu_build::animated::Animator>,
    /// With --brush: Ctrl + left click edits the voxel under the cursor.
    pub(super) brush: Option<super::super::brush::Brush>,
    /// The animation clock's start.
    pub(super) started: Instant,
    pub(super) watcher: PipelineWatcher,
    /// Under a GPU budget: how the scene streams.
    pub(super) streaming: Option<ssbvb_gpu::scene::StreamingOptions>,
    /// Knob edits by pass name, applied over the file's pipeline.
    pub(super) knob_edits: BTreeMap<String, PassKind>,
    pub(super) rig: CameraRig,
    pub(super) initial_camera: Camera,
    pub(super) input: CameraInput,
    /// Last cursor position in physical pixels.
    pub(super) cursor: Option<(f64, f64)>,
    pub(super) stats: Stats,
    pub(super) overlay: OverlayState,
    pub(super) error: Option<String>,
    pub(super) status: Option<String>,
    pub(super) frame: u64,
    /// Frame number of the last renderer rebuild (timings are sampled from there).
    pub(super) sample_base: u64,
    pub(super) last_frame: Instant,
    pub(super) last_poll: Instant,
    pub(super) needs_rebuild: bool,
    pub(super) screenshot_next: Option<PathBuf>,
    pub(super) screenshot_written: bool,
    /// Pipeline reloads that succeeded and that failed (the last good one kept).
    pub(super) reloads: (u64, u64),
    /// Memory after the warm-up, for `--memory-report`.
    pub(super) memory_samples: Vec<crate::soak::Sample>,
    /// What the last GPU fault did (kept on screen).
    pub(super) notice: Option<String>,
    /// Devices recreated so far, and the rule on repeated losses.
    pub(super) recoveries: Recoveries,
    /// The frame whose injected faults were applied (each fires once).
    pub(super) faults_injected_at: Option<u64>,
}

/// Why the GPU side is made again.
pub(super) enum Fault {
    /// The device was lost, for this reason.
    Lost(String),
    /// `oom@FRAME`: the new device refuses its first large allocation.
    OutOfMemory,
}
