//! Screenshots of what the window shows, overlay included: the frame is drawn a second
//! time (same blit, same egui primitives) into a texture that can be read back, because a
//! surface texture cannot be copied from on every platform.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use ssbvb_gpu::{GpuContext, wgpu};

/// A texture like the surface's (format, size) that can be drawn into and read back.
pub fn target(ctx: &GpuContext, format: wgpu::TextureFormat, size: (u32, u32)) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("view screenshot"),
        size: wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// Reads `texture` back (after the frame that drew it was submitted) and writes it as a
/// PNG at `path` (atomically: a temporary file renamed into place).
pub fn write(ctx: &GpuContext, texture: &wgpu::Texture, path: &Path) -> Result<()> {
    let data = ctx.read_texture(texture, wgpu::TextureAspect::All)?;
    let rgba = crate::render_cmd::to_rgba8(&data)?;
    ssbvb_gpu::readback::write_png_rgba8(path, texture.width(), texture.height(), &rgba)
        .with_context(|| format!("writing screenshot {}", path.display()))?;
    Ok(())
}

/// A fresh screenshot name in the current folder for the F12 key.
pub fn default_path() -> PathBuf {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let mut path = PathBuf::from(format!("ssbvb-view-{secs}.png"));
    let mut n = 1;
    while path.exists() {
        path = PathBuf::from(format!("ssbvb-view-{secs}-{n}.png"));
        n += 1;
    }
    path
}
