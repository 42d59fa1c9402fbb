//! What a rendered frame shows, per pixel, for accuracy against the CPU reference
//! (`ssbvb_voxel::accuracy`): read back from the G-buffer and, when the pipeline has a
//! ray-march filter, the voxel of each pixel's SSBVB slot.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_voxel::accuracy::GpuHit;

use crate::error::PassError;
use crate::kinds::gbuffer::{STENCIL_VOXEL, count_stencil};
use crate::runtime::renderer::Renderer;

pub mod lighting;
pub mod ssbvb;

/// IEEE half → f32.
pub fn f16_to_f32(h: u16) -> f32 {
    let s = if h >> 15 == 1 { -1.0 } else { 1.0 };
    let e = ((h >> 10) & 0x1f) as i32;
    let m = (h & 0x3ff) as f32;
    match e {
        0 => s * m * 2f32.powi(-24),
        31 if m == 0.0 => s * f32::INFINITY,
        31 => f32::NAN,
        _ => s * (1.0 + m / 1024.0) * 2f32.powi(e - 15),
    }
}

pub(crate) fn read(
    ctx: &GpuContext,
    r: &Renderer,
    name: &str,
) -> Result<ssbvb_gpu::readback::TextureData, PassError> {
    let i = r.resource(name).ok_or_else(|| {
        PassError::BadScene(format!(
            "the pipeline has no live resource `{name}` to measure"
        ))
    })?;
    Ok(ctx.read_texture(&r.resources.texture(i).texture, wgpu::TextureAspect::All)?)
}

/// Per pixel of the last frame (row-major, row 0 at the top): the hit the G-buffer shows
/// (`gbuffer_albedo` alpha > 0), its distance from the eye (from `gbuffer_position`), its
/// geometric normal (`gbuffer_geometric_normal`, [`geometric_normals`]) and, with a filter, the voxel cell
/// of the SSBVB slot its pixel's ray filled (else `[u32::MAX; 3]`, which never counts as
/// the same voxel; meaningful only for a filter at screen resolution without
/// `unique_voxels`, whose slots are one per covered pixel).
/// Instance 0 is assumed (single-instance scenes; [`gbuffer_hits_in`] names instances).
pub fn gbuffer_hits(ctx: &GpuContext, r: &Renderer) -> Result<Vec<Option<GpuHit>>, PassError> {
    hits(ctx, r, None)
}

/// [`gbuffer_hits`] with each hit's instance (its index in the scene's flattened instance
/// list, as the reference numbers them) taken from the SSBVB slot of its pixel through the
/// frame's visible instances of `scene`; needs a filter (an error without one).
pub fn gbuffer_hits_in(
    ctx: &GpuContext,
    r: &Renderer,
    scene: &ssbvb_gpu::scene::GpuScene,
) -> Result<Vec<Option<GpuHit>>, PassError> {
    if !ssbvb::has_ssbvb(r) {
        return Err(PassError::BadScene(
            "naming the instance of each pixel needs a pipeline with an SSBVB".into(),
        ));
    }
    hits(ctx, r, Some(scene))
}

fn hits(
    ctx: &GpuContext,
    r: &Renderer,
    scene: Option<&ssbvb_gpu::scene::GpuScene>,
) -> Result<Vec<Option<GpuHit>>, PassError> {
    let albedo = read(ctx, r, "gbuffer_albedo")?;
    let pos = read(ctx, r, "gbuffer_position")?.as_f32();
    let normal = geometric_normals(&read(ctx, r, "gbuffer_geometric_normal")?)?;
    let n = (albedo.width * albedo.height) as usize;
    let mut cells = vec![[u32::MAX; 3]; n];
    let mut instances = vec![0u32; n];
    if ssbvb::has_ssbvb(r) {
        for s in ssbvb::read_slots(ctx, r)? {
            if let Some(c) = cells.get_mut(s.pixel as usize) {
                *c = s.voxel.cell();
            }
            if let Some(scene) = scene {
                let Some(v) = scene.visible.get(s.instance as usize) else {
                    return Err(PassError::BadScene(format!(
                        "a slot names visible instance {}, the frame has {}",
                        s.instance,
                        scene.visible.len()
                    )));
                };
                if let Some(i) = instances.get_mut(s.pixel as usize) {
                    *i = v.scene_index;
                }
            }
        }
    }
    Ok((0..n)
        .map(|i| {
            (albedo.bytes[i * 4 + 3] > 0).then(|| {
                let p = &pos[i * 4..i * 4 + 3];
                GpuHit {
                    instance: instances[i],
                    cell: cells[i],
                    t: (p[0] as f64).hypot(p[1] as f64).hypot(p[2] as f64),
                    normal: normal[i],
                }
            })
        })
        .collect())
}

/// The unit vectors of a read-back geometric-normal target (`Rg16Float` octahedral codes,
/// see [`crate::kinds::gbuffer`]); an error for any other format.
pub fn geometric_normals(t: &ssbvb_gpu::readback::TextureData) -> Result<Vec<[f32; 3]>, PassError> {
    if t.format != wgpu::TextureFormat::Rg16Float {
        return Err(PassError::BadScene(format!(
            "a geometric normal target must be Rg16Float, not {:?}",
            t.format
        )));
    }
    Ok(t.bytes
        .chunks_exact(4)
        .map(|c| {
            let h = |i: usize| f16_to_f32(u16::from_le_bytes([c[i], c[i + 1]]));
            crate::kinds::gbuffer::oct_decode([h(0), h(2)])
        })
        .collect())
}

/// Pixels of the last frame that show a voxel: stencil = voxel in the pipeline's
/// `depth_stencil` resource (triangle objects and background excluded) — what the SSBVB
/// fill count is compared with. `None` when the pipeline has no live `depth_stencil`.
pub fn voxel_pixels(ctx: &GpuContext, r: &Renderer) -> Result<Option<usize>, PassError> {
    let Some(i) = r.resource("depth_stencil") else {
        return Ok(None);
    };
    let count = count_stencil(ctx, &r.resources.texture(i).texture, STENCIL_VOXEL)?;
    Ok(count.map(|c| c as usize))
}

/// Per pixel, 1 where the stencil says a voxel was drawn and 0 elsewhere (rows top to
/// bottom), from the pipeline's `depth_stencil`; `None` without one. The coverage the page
/// and `ssbvb render --voxel-mask` compare.
pub fn voxel_mask(ctx: &GpuContext, r: &Renderer) -> Result<Option<Vec<u8>>, PassError> {
    match voxel_mask_texture(r) {
        Some(t) => pollster::block_on(read_voxel_mask_async(ctx, &t)).map(Some),
        None => Ok(None),
    }
}

/// The texture [`voxel_mask`] reads: the pipeline's `depth_stencil`, when it has one with
/// a stencil.
pub fn voxel_mask_texture(r: &Renderer) -> Option<wgpu::Texture> {
    let texture = &r.resources.texture(r.resource("depth_stencil")?).texture;
    texture
        .format()
        .is_depth_stencil_format()
        .then(|| texture.clone())
}

/// [`voxel_mask`] of a [`voxel_mask_texture`], awaiting the readback (the browser's form).
pub async fn read_voxel_mask_async(
    ctx: &GpuContext,
    depth_stencil: &wgpu::Texture,
) -> Result<Vec<u8>, PassError> {
    let stencil = ctx
        .read_texture_async(depth_stencil, wgpu::TextureAspect::StencilOnly)
        .await?;
    let voxel = STENCIL_VOXEL as u8;
    Ok(stencil
        .bytes
        .iter()
        .map(|&s| u8::from(s == voxel))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::f16_to_f32;

    /// An independent decoder: the f16 bit fields moved into f32's (exponent rebiased,
    /// subnormals normalized), no arithmetic on values.
    fn by_bits(h: u16) -> f32 {
        let sign = u32::from(h >> 15) << 31;
        let exp = u32::from((h >> 10) & 0x1f);
        let mant = u32::from(h & 0x3ff);
        let bits = match (exp, mant) {
            (0, 0) => sign,
            (0, m) => {
                // Subnormal: shift the mantissa up until its leading one is the hidden bit.
                let shift = m.leading_zeros() - 21;
                let m = (m << shift) & 0x3ff;
                sign | ((127 - 15 + 1 - shift) << 23) | (m << 13)
            }
            (31, 0) => sign | 0x7f80_0000,
            (31, m) => sign | 0x7f80_0000 | (m << 13),
            (e, m) => sign | ((e + 127 - 15) << 23) | (m << 13),
        };
        f32::from_bits(bits)
    }

    #[test]
    fn every_half_decodes_like_the_bit_level_conversion() {
        for h in 0..=u16::MAX {
            let (a, b) = (f16_to_f32(h), by_bits(h));
            if b.is_nan() {
                assert!(a.is_nan(), "{h:#06x}: {a}");
            } else {
                assert_eq!(a.to_bits(), b.to_bits(), "{h:#06x}: {a} vs {b}");
            }
        }
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x7bff), 65504.0);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
    }
}
