//! What the page draws with: the device, the scene on it, the renderer, the orbit camera,
//! and the canvas it presents to.

use glam::DVec3;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{GpuScene, Scene};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::{FrameStats, Profiling, Renderer};
use ssbvb_voxel::camera::Camera;

use crate::WebError;
use crate::present::Presenter;

/// A camera orbiting a point: drag turns it, the wheel moves it nearer or farther.
#[derive(Debug, Clone, Copy)]
pub struct Orbit {
    base: Camera,
    target: DVec3,
    distance: f64,
    yaw: f64,
    pitch: f64,
}

impl Orbit {
    /// The orbit through `camera`'s eye around its look-at point.
    pub fn of(camera: Camera) -> Self {
        let offset = camera.position - camera.look_at;
        let distance = offset.length().max(1e-6);
        Orbit {
            base: camera,
            target: camera.look_at,
            distance,
            yaw: offset.x.atan2(offset.z),
            pitch: (offset.y / distance).clamp(-1.0, 1.0).asin(),
        }
    }

    /// Turns by a drag of `(dx, dy)` pixels.
    pub fn drag(&mut self, dx: f64, dy: f64) {
        self.yaw -= dx * 0.008;
        self.pitch = (self.pitch + dy * 0.008).clamp(-1.5, 1.5);
    }

    /// Moves nearer (`steps` < 0) or farther.
    pub fn zoom(&mut self, steps: f64) {
        self.distance = (self.distance * (steps * 0.001).exp()).clamp(1e-3, 1e4);
    }

    /// The camera now. Untouched, it is the scene's camera exactly (no round trip through
    /// angles), so the first frame matches `ssbvb render`'s.
    pub fn camera(&self, touched: bool) -> Camera {
        if !touched {
            return self.base;
        }
        let dir = DVec3::new(
            self.pitch.cos() * self.yaw.sin(),
            self.pitch.sin(),
            self.pitch.cos() * self.yaw.cos(),
        );
        Camera {
            position: self.target + dir * self.distance,
            ..self.base
        }
    }
}

/// The GPU side of the page.
pub struct View {
    /// The scene on the device.
    pub scene: GpuScene,
    /// The pipeline's renderer.
    pub renderer: Renderer,
    /// The camera.
    pub orbit: Orbit,
    /// Whether the user moved the camera.
    pub touched: bool,
    /// The canvas, where the page presents (none in a headless browser).
    pub presenter: Option<Presenter>,
    /// Whether the next animation frame must draw.
    pub dirty: bool,
}

impl View {
    /// Uploads `scene` and builds `pipeline`'s renderer at `size`; it presents through
    /// `presenter` when there is one (set up for frames of that size and pipeline).
    pub fn open(
        ctx: &GpuContext,
        scene: Scene,
        camera: Camera,
        pipeline: ResolvedPipeline,
        size: (u32, u32),
        presenter: Option<Presenter>,
    ) -> Result<Self, WebError> {
        let gpu = |e: &dyn std::fmt::Display| WebError::Gpu(e.to_string());
        let scene =
            ssbvb_engine::upload::upload_scene(ctx, scene, ssbvb_engine::upload::Residency::Whole)
                .map_err(|e| gpu(&e))?;
        let renderer =
            ssbvb_engine::upload::renderer(ctx, &scene, pipeline, size).map_err(|e| gpu(&e))?;
        Ok(View {
            scene,
            renderer,
            orbit: Orbit::of(camera),
            touched: false,
            presenter,
            dirty: true,
        })
    }

    /// Renders at `size` from now on (the canvas was resized): the renderer's frame
    /// resources and the canvas's configuration are made again.
    pub fn resize(&mut self, ctx: &GpuContext, size: (u32, u32)) -> Result<(), WebError> {
        let pipeline = self.renderer.pipeline.clone();
        self.renderer = ssbvb_engine::upload::renderer(ctx, &self.scene, pipeline, size)
            .map_err(|e| WebError::Gpu(e.to_string()))?;
        if let Some(p) = self.presenter.take() {
            let output = &self.renderer.output().texture;
            self.presenter = Some(Presenter::new(ctx, p.into_surface(), output)?);
        }
        self.dirty = true;
        Ok(())
    }

    /// Draws a frame (with per-pass timestamps where the device has them) and presents it.
    pub fn draw(&mut self, ctx: &GpuContext) -> Result<FrameStats, WebError> {
        let camera = self.orbit.camera(self.touched);
        let stats = self
            .renderer
            .render(ctx, &mut self.scene, &camera, Profiling::TimestampsUnwaited)
            .map_err(|e| WebError::Gpu(e.to_string()))?;
        if let Some(p) = &self.presenter {
            p.present(ctx, &self.renderer.output().texture)?;
        }
        self.dirty = false;
        Ok(stats)
    }
}
