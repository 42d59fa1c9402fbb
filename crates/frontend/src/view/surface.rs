//! The GPU side of the window: an instance that can present, an adapter that supports
//! the window's surface, the device (through [`GpuContext::from_adapter`], so the viewer
//! gets the same features, limits and error capture as `ssbvb render`), and the surface
//! configuration.

use std::sync::Arc;

use anyhow::{Context, Result, anyhow};
use ssbvb_gpu::{AdapterChoice, GpuContext, Requirements, wgpu};
use winit::window::Window;

/// A device and the window's surface.
pub struct WindowGpu {
    /// The device (and the instance the surface belongs to).
    pub ctx: GpuContext,
    /// The window's surface.
    pub surface: wgpu::Surface<'static>,
    /// Its current configuration (size follows the window).
    pub config: wgpu::SurfaceConfiguration,
}

impl WindowGpu {
    /// Creates the surface of `window` and a device that can present to it and has what
    /// `requirements` (the pipeline's) asks. `display` is the event loop's display
    /// connection (GL on Wayland needs it at instance creation).
    pub fn new(
        window: Arc<Window>,
        display: winit::event_loop::OwnedDisplayHandle,
        requirements: &Requirements,
    ) -> Result<Self> {
        let mut desc = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(display));
        desc.backends = wgpu::Backends::VULKAN
            | wgpu::Backends::GL
            | wgpu::Backends::METAL
            | wgpu::Backends::DX12;
        desc.flags = wgpu::InstanceFlags::VALIDATION | wgpu::InstanceFlags::DEBUG;
        // WGPU_BACKEND narrows the backends, WGPU_VALIDATION=0 turns validation off.
        let desc = desc.with_env();
        let backends = desc.backends;
        let instance = wgpu::Instance::new(desc);
        let size = window.inner_size();
        let surface = instance.create_surface(window).map_err(|e| {
            anyhow!(super::display::no_display_message(&format!(
                "cannot create a surface for the window: {e}"
            )))
        })?;
        let choice = AdapterChoice::parse(&std::env::var("SSBVB_ADAPTER").unwrap_or_default());
        let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
        let seen: Vec<String> = adapters
            .iter()
            .map(|a| format!("{} [{:?}]", a.get_info().name, a.get_info().backend))
            .collect();
        adapters.retain(|a| a.is_surface_supported(&surface) && choice.allows(&a.get_info()));
        adapters.sort_by_key(|a| ssbvb_gpu::rank(&a.get_info()));
        let (adapter, verdict) =
            ssbvb_gpu::first_fitting(adapters, requirements, crate::adapter_cmd::limits())
                .map_err(|refused| {
                    anyhow!(
                        "no GPU adapter can present to the window and run the pipeline (backends \
                 {backends:?}, SSBVB_ADAPTER {choice:?}, adapters seen: {}{}); {}",
                        if seen.is_empty() {
                            "none".into()
                        } else {
                            seen.join(", ")
                        },
                        if refused.is_empty() {
                            String::new()
                        } else {
                            format!("; {}", refused.join(" | "))
                        },
                        ssbvb_gpu::NO_ADAPTER_HINT
                    )
                })?;
        let ctx = GpuContext::from_adapter_with(
            instance,
            adapter,
            verdict.fallback_notes(),
            crate::adapter_cmd::limits(),
        )?;
        let caps = surface.get_capabilities(&ctx.adapter);
        // An sRGB format when there is one (hardware encoding); the blit shader and egui
        // encode themselves otherwise.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .context("the surface reports no texture format")?;
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
            // Plain sRGB output (what the renderer's Rgba8UnormSrgb frame is).
            color_space: Default::default(),
        };
        ctx.validated("configuring the window surface", |d| {
            surface.configure(d, &config)
        })?;
        Ok(Self {
            ctx,
            surface,
            config,
        })
    }

    /// Reconfigures the surface for a new window size (zero sizes are skipped: minimized).
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        if width == 0 || height == 0 {
            return Ok(());
        }
        self.config.width = width;
        self.config.height = height;
        self.ctx.validated("resizing the window surface", |d| {
            self.surface.configure(d, &self.config)
        })?;
        Ok(())
    }

    /// Window size in pixels as configured.
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }
}
