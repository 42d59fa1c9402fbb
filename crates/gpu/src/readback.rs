//! Copies of GPU textures and buffers to the CPU, and PNG output.

use std::path::Path;

use crate::{GpuContext, GpuError};

/// A texture read back to the CPU, rows tightly packed (padding removed).
#[derive(Debug, Clone, PartialEq)]
pub struct TextureData {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Format of the texels (of the aspect read).
    pub format: wgpu::TextureFormat,
    /// Bytes per texel.
    pub bytes_per_texel: u32,
    /// `width * height * bytes_per_texel` bytes, row 0 at the top.
    pub bytes: Vec<u8>,
}

impl TextureData {
    /// The texel at `(x, y)` as bytes.
    pub fn texel(&self, x: u32, y: u32) -> &[u8] {
        let b = self.bytes_per_texel as usize;
        let i = (y as usize * self.width as usize + x as usize) * b;
        &self.bytes[i..i + b]
    }

    /// Texels as `f32`s (for float formats; `Rgba32Float` gives 4 per texel).
    pub fn as_f32(&self) -> Vec<f32> {
        bytemuck::pod_collect_to_vec(&self.bytes)
    }

    /// Texels as `u32`s.
    pub fn as_u32(&self) -> Vec<u32> {
        bytemuck::pod_collect_to_vec(&self.bytes)
    }

    /// An 8-bit RGBA or BGRA image as RGBA8 bytes, rows top to bottom, with the encoding
    /// the texels have (sRGB formats' bytes are sRGB-encoded): what a PNG of the frame
    /// holds. Other formats are an error.
    pub fn to_rgba8(&self) -> Result<Vec<u8>, GpuError> {
        use wgpu::TextureFormat as F;
        match self.format {
            F::Rgba8Unorm | F::Rgba8UnormSrgb => Ok(self.bytes.clone()),
            F::Bgra8Unorm | F::Bgra8UnormSrgb => Ok(self
                .bytes
                .chunks(4)
                .flat_map(|p| [p[2], p[1], p[0], p[3]])
                .collect()),
            other => Err(GpuError::Readback {
                label: format!("{other:?}"),
                message: "only an 8-bit RGBA/BGRA output can be written as an RGBA8 image".into(),
            }),
        }
    }
}

/// Bytes per row of a texel copy must be a multiple of this.
pub const ROW_ALIGN: u32 = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;

impl GpuContext {
    /// Reads mip 0, layer 0 of a 2D texture (the given aspect) back to the CPU.
    pub fn read_texture(
        &self,
        texture: &wgpu::Texture,
        aspect: wgpu::TextureAspect,
    ) -> Result<TextureData, GpuError> {
        pollster::block_on(self.read_texture_async(texture, aspect))
    }

    /// [`GpuContext::read_texture`] awaiting the mapping: the form for the browser, whose
    /// thread must not block (natively the device is waited for first, so the future is
    /// ready when first polled).
    pub async fn read_texture_async(
        &self,
        texture: &wgpu::Texture,
        aspect: wgpu::TextureAspect,
    ) -> Result<TextureData, GpuError> {
        let (width, height) = (texture.width(), texture.height());
        let format = texture
            .format()
            .aspect_specific_format(aspect)
            .unwrap_or(texture.format());
        let bpt = format
            .block_copy_size(Some(aspect))
            .ok_or_else(|| GpuError::Readback {
                label: format!("{format:?}"),
                message: "this format/aspect cannot be copied to a buffer".into(),
            })?;
        let row = width * bpt;
        let padded = row.div_ceil(ROW_ALIGN) * ROW_ALIGN;
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: padded as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        self.validated("texture readback", |d| {
            let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
            enc.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: &staging,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(padded),
                        rows_per_image: Some(height),
                    },
                },
                wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
            );
            self.submit("texture readback", [enc.finish()]);
        })?;
        let data = self.map_read(&staging, "texture").await?;
        let mut bytes = Vec::with_capacity((row * height) as usize);
        for y in 0..height as usize {
            let start = y * padded as usize;
            bytes.extend_from_slice(&data[start..start + row as usize]);
        }
        Ok(TextureData {
            width,
            height,
            format,
            bytes_per_texel: bpt,
            bytes,
        })
    }

    /// Reads a whole buffer (it needs `COPY_SRC` usage) back to the CPU.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        pollster::block_on(self.read_buffer_async(buffer))
    }

    /// [`GpuContext::read_buffer`] awaiting the mapping (see
    /// [`GpuContext::read_texture_async`]).
    pub async fn read_buffer_async(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        let size = buffer.size();
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        self.validated("buffer readback", |d| {
            let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
            enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
            self.submit("buffer readback", [enc.finish()]);
        })?;
        self.map_read(&staging, "buffer").await
    }

    async fn map_read(&self, staging: &wgpu::Buffer, label: &str) -> Result<Vec<u8>, GpuError> {
        let failed = |message: String| GpuError::Readback {
            label: label.into(),
            message,
        };
        let (tx, rx) = futures_channel::oneshot::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        // Natively the callback runs inside a poll; the browser runs it on its own.
        if !cfg!(target_arch = "wasm32") {
            self.wait_idle()?;
        }
        match rx.await {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(failed(e.to_string())),
            Err(e) => return Err(failed(e.to_string())),
        }
        let out = staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| failed(e.to_string()))?
            .to_vec();
        staging.unmap();
        Ok(out)
    }
}

/// Writes RGBA8 pixels (row 0 at the top) as a PNG, atomically: a temporary file in the
/// same folder is renamed over `path`, so an existing file is never left half-written.
pub fn write_png_rgba8(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), GpuError> {
    let err = |message: String| GpuError::Write {
        path: path.display().to_string(),
        message,
    };
    if rgba.len() != width as usize * height as usize * 4 {
        return Err(err(format!(
            "{} bytes for {width}x{height} RGBA8",
            rgba.len()
        )));
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".ssbvb-")
        .suffix(".png.tmp")
        .tempfile_in(dir)
        .map_err(|e| err(e.to_string()))?;
    {
        let enc = image::codecs::png::PngEncoder::new(std::io::BufWriter::new(tmp.as_file_mut()));
        image::ImageEncoder::write_image(enc, rgba, width, height, image::ExtendedColorType::Rgba8)
            .map_err(|e| err(e.to_string()))?;
    }
    tmp.as_file().sync_all().map_err(|e| err(e.to_string()))?;
    // tempfile creates files 0600; an image is an ordinary user file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(0o644))
            .map_err(|e| err(e.to_string()))?;
    }
    tmp.persist(path).map_err(|e| err(e.error.to_string()))?;
    Ok(())
}
