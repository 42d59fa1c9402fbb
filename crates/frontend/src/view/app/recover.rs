//! The viewer after a GPU fault: a lost device (a driver reset, the GPU removed, or
//! `--inject-fault device-lost@FRAME`) or `--inject-fault oom@FRAME`. Everything on the
//! device is dropped and made again from what stays on the CPU: the scene (with the LOD
//! policies set in the overlay), the pipeline file with its knob edits, the camera, the
//! budget (pages stream in again over the next frames) and the brush edits, replayed in
//! order so the rooms end as they were. The overlay and the window title say it happened.
//! A device lost again within [`ssbvb_engine::faults::LOST_AGAIN_WITHIN`] frames ends the viewer
//! with an error.

use anyhow::Result;

use super::open::GpuParts;
use super::state::{Fault, Loaded, Options, Viewer};

/// What the window title gains after a recovery.
const RECOVERED: &str = "recovered from a GPU fault";

impl Viewer {
    /// The device's fault before this frame, if any: an injected one now (each once), or a
    /// loss wgpu reported.
    pub(super) fn fault_now(&mut self, options: &Options) -> Option<Fault> {
        let frame = self.frame as usize;
        if self.faults_injected_at != Some(self.frame) {
            self.faults_injected_at = Some(self.frame);
            if ssbvb_engine::faults::loses_device_at(&options.faults, frame) {
                self.gpu.ctx.inject_device_loss();
            }
            if frame > 0 && ssbvb_engine::faults::runs_out_of_memory_at(&options.faults, frame) {
                return Some(Fault::OutOfMemory);
            }
        }
        self.gpu.ctx.lost().map(Fault::Lost)
    }

    /// The viewer on a new device after `fault`, its CPU-side state kept.
    pub(super) fn recovered(mut self, fault: Fault) -> Result<Viewer> {
        let frame = self.frame;
        if let Fault::Lost(reason) = &fault {
            self.recoveries.lost_at(frame as usize, reason)?;
            eprintln!("view: the GPU device was lost at frame {frame} ({reason}); recreating it");
        }
        let scene = std::mem::take(&mut self.scene.scene);
        let edits = self
            .brush
            .as_ref()
            .map(|b| b.history().to_vec())
            .unwrap_or_default();
        let brush = self.brush.as_mut().map(|b| b.restarted(&scene));
        // What is on screen: an edit or reload whose rebuild failed never drew.
        let pipeline = self.renderer.pipeline.clone();
        let Viewer {
            window,
            display,
            gpu,
            blit,
            egui_ctx,
            egui_state,
            egui_renderer,
            scene: old_scene,
            renderer,
            animator,
            brush: old_brush,
            watcher,
            streaming,
            animated,
            rig,
            initial_camera,
            knob_edits,
            overlay,
            reloads,
            memory_samples,
            recoveries,
            started,
            screenshot_written,
            screenshot_next,
            cursor,
            faults_injected_at,
            ..
        } = self;
        // The old device's objects go before the new device asks for memory.
        drop((renderer, old_scene, animator, old_brush));
        drop((blit, egui_renderer, egui_state));
        drop((egui_ctx, gpu));
        let mut loaded = Loaded {
            scene,
            camera: initial_camera,
            watcher,
            streaming,
            animated,
            brush,
        };
        let refuse = matches!(fault, Fault::OutOfMemory);
        let (parts, lowered) =
            GpuParts::open_within_memory(&window, &display, &mut loaded, pipeline, refuse)?;
        let mut v = Viewer::assemble(window, display, parts, loaded);
        v.rig = rig;
        v.initial_camera = initial_camera;
        v.knob_edits = knob_edits;
        v.overlay = overlay;
        v.frame = frame;
        v.sample_base = frame;
        v.reloads = reloads;
        v.memory_samples = memory_samples;
        v.recoveries = recoveries;
        v.started = started;
        v.screenshot_written = screenshot_written;
        v.screenshot_next = screenshot_next;
        v.cursor = cursor;
        if !lowered.is_empty() {
            v.overlay.forget_budget_draft();
        }
        v.faults_injected_at = faults_injected_at;
        if let Some(b) = &mut v.brush {
            b.replay(&v.gpu.ctx, &mut v.scene, &edits)?;
        }
        let notice = match fault {
            Fault::Lost(reason) => format!(
                "GPU device lost at frame {frame} ({reason}); recovered on a new device with \
                 the scene, pipeline, camera and {} brush edits",
                edits.len()
            ),
            Fault::OutOfMemory if lowered.is_empty() => {
                format!("frame {frame}: the GPU session was rebuilt (oom@{frame})")
            }
            Fault::OutOfMemory => {
                format!("out of GPU memory at frame {frame}: {}", lowered.join("; "))
            }
        };
        eprintln!("view: {notice}");
        let title = v.window.title();
        if !title.ends_with(RECOVERED) {
            v.window.set_title(&format!("{title} — {RECOVERED}"));
        }
        v.notice = Some(notice);
        Ok(v)
    }
}
