//! The end of a viewer frame: the renderer's output and the overlay onto the window's
//! surface (and onto a screenshot target), the screenshot written, the memory report and
//! the `--frames` limit.

use std::time::Instant;

use anyhow::{Result, anyhow};
use ssbvb_gpu::wgpu;

use super::super::capture;
use super::state::{Flow, Options, Viewer};

impl Viewer {
    /// Draws the frame and the overlay onto the surface (and the screenshot target).
    pub(super) fn present(
        &mut self,
        options: &Options,
        shapes: Vec<egui::epaint::ClippedShape>,
        pixels_per_point: f32,
    ) -> Result<Flow> {
        let (surface_texture, suboptimal) = match self.gpu.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => (t, false),
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => (t, true),
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(Flow::Continue);
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.sync_size()?;
                return Ok(Flow::Continue);
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                return Err(anyhow!("the window surface reported a validation error"));
            }
        };
        let ctx = &self.gpu.ctx;
        let paint_jobs = self.egui_ctx.tessellate(shapes, pixels_per_point);
        let (w, h) = self.gpu.size();
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [w, h],
            pixels_per_point,
        };
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("view present"),
            });
        self.blit
            .copy_frame(ctx, &mut encoder, &self.renderer.output().texture);
        let callbacks = self.egui_renderer.update_buffers(
            &ctx.device,
            &ctx.queue,
            &mut encoder,
            &paint_jobs,
            &screen,
        );
        let surface_view = surface_texture.texture.create_view(&Default::default());
        let shot = self
            .screenshot_next
            .take()
            .map(|path| (path, capture::target(ctx, self.gpu.config.format, (w, h))));
        let shot_view = shot
            .as_ref()
            .map(|(_, t)| t.create_view(&Default::default()));
        for target in std::iter::once(&surface_view).chain(shot_view.as_ref()) {
            self.blit.draw(&mut encoder, target);
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                })
                .forget_lifetime();
            self.egui_renderer.render(&mut pass, &paint_jobs, &screen);
        }
        ctx.submit(
            "view present",
            callbacks.into_iter().chain([encoder.finish()]),
        );
        self.window.pre_present_notify();
        ctx.queue.present(surface_texture);
        if suboptimal {
            self.sync_size()?;
        }
        let ctx = &self.gpu.ctx;
        let errors = ctx.take_uncaptured_errors();
        if !errors.is_empty() {
            return Err(anyhow!(
                "wgpu error while presenting: {}",
                errors.join("; ")
            ));
        }
        if let Some((path, texture)) = shot {
            match capture::write(ctx, &texture, &path) {
                Ok(()) => {
                    self.status = Some(format!("wrote {}", path.display()));
                    if options.screenshot.as_ref() == Some(&path) {
                        self.screenshot_written = true;
                    }
                }
                // An automation screenshot that fails is a failed run; an F12 one is not.
                Err(e) if options.screenshot.as_ref() == Some(&path) => return Err(e),
                Err(e) => self.error = Some(format!("{e:#}")),
            }
        }
        self.stats.presented(Instant::now());
        self.frame += 1;

        if let (Some(limit), Some(path)) = (options.frames, &options.memory_report) {
            let warmup = crate::soak::warmup_frames(limit as usize) as u64;
            let every = (limit / 9).max(1);
            // Written at every sample (the report so far), so a run that dies leaves its
            // last state, and a watcher knows the viewer is up.
            let sample = self.frame >= warmup && (self.frame - warmup).is_multiple_of(every);
            if sample || self.frame >= limit {
                let s = crate::soak::Sample::take(&self.gpu.ctx, &self.scene, self.frame as usize)?;
                let report = crate::soak::ViewMemoryReport {
                    frames: self.frame,
                    reloads_ok: self.reloads.0,
                    reloads_failed: self.reloads.1,
                    memory: crate::soak::MemoryTrend::of(self.memory_samples.clone(), s),
                };
                self.memory_samples.push(s);
                crate::soak::write_json(path, &report)?;
            }
        }
        // Automation: exit after the last frame (its screenshot was taken above).
        if options.frames.is_some_and(|limit| self.frame >= limit) {
            return Ok(Flow::Exit);
        }
        Ok(Flow::Continue)
    }
}
