//! The cone tracer's error, measured: after a frame of a pipeline with `ConeTrace` and
//! `ConeComposite`, every `stride`-th pixel that shows something is lit again on the CPU
//! with the Monte Carlo reference ([`ssbvb_voxel::lighting::monte_carlo`]) at the G-buffer
//! sample the GPU used (its position and the normal the cone pass read), and both the
//! three terms and the lit colour are compared.

use glam::DVec3;
use rayon::prelude::*;
use ssbvb_gpu::GpuContext;
use ssbvb_graph::PassKind;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::lighting::monte_carlo::monte_carlo;
use ssbvb_voxel::lighting::{LightingParams, LightingSample};
use ssbvb_voxel::reference::{Instance, Tracer};
use ssbvb_voxel::shading::{Lit, linear_to_srgb8, shade_lit, srgb_to_linear};

use crate::error::PassError;
use crate::measure::{f16_to_f32, read};
use crate::runtime::renderer::Renderer;
use ssbvb_gpu::scene::Scene;
use ssbvb_gpu::scene::choose_level;

/// One compared pixel.
#[derive(Debug, Clone, Copy)]
pub struct LitPixel {
    /// Row-major pixel index.
    pub index: usize,
    /// What the cone tracer wrote.
    pub gpu: LightingSample,
    /// The Monte Carlo reference at the same sample.
    pub reference: LightingSample,
    /// The composite's output (sRGB8) and the reference lit with [`shade_lit`] (sRGB8).
    pub color: ([u8; 3], [u8; 3]),
    /// The cone pass traced this pixel itself (always at full resolution; one pixel of
    /// each block at a lower one, the others are upsampled by the composite).
    pub traced: bool,
}

/// Errors of the cone tracer against the Monte Carlo reference: AO, shadow and bounce over
/// the compared pixels the cone pass traced (its estimate), the lit colour over all of
/// them (what the composite shows, upsampling included).
#[derive(Debug, Clone)]
pub struct LightingReport {
    /// The compared pixels.
    pub pixels: Vec<LitPixel>,
    /// Mean absolute AO error.
    pub ao_mae: f64,
    /// Mean signed AO error (GPU − reference): positive = the cones see too little.
    pub ao_bias: f64,
    /// Mean absolute light-visibility error.
    pub shadow_mae: f64,
    /// Mean absolute bounce error over the three channels.
    pub indirect_mae: f64,
    /// Mean absolute error of the lit colour, linear, over the three channels.
    pub lit_mae: f64,
    /// PSNR (dB) of the composite's sRGB8 output against the reference lit the same way.
    pub lit_psnr: f64,
}

/// The `(max_distance, shadow_aperture)` of the pipeline's cone tracer, if it has one.
pub fn cone_knobs(r: &Renderer) -> Option<(f64, f64)> {
    r.pipeline.passes.iter().find_map(|p| match &p.kind {
        PassKind::ConeTrace(k) => Some((f64::from(k.max_distance), f64::from(k.shadow_aperture))),
        _ => None,
    })
}

/// Texels of an Rgba16Float or Rgba32Float texture.
fn float4(t: &ssbvb_gpu::readback::TextureData) -> Vec<[f32; 4]> {
    match t.format {
        ssbvb_gpu::wgpu::TextureFormat::Rgba32Float => t
            .as_f32()
            .chunks(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
        _ => half4(&t.bytes),
    }
}

/// The output as RGBA8 (BGRA swapped); other formats are refused.
fn rgba8(t: ssbvb_gpu::readback::TextureData) -> Result<Vec<u8>, PassError> {
    use ssbvb_gpu::wgpu::TextureFormat as F;
    match t.format {
        F::Rgba8Unorm | F::Rgba8UnormSrgb => Ok(t.bytes),
        F::Bgra8Unorm | F::Bgra8UnormSrgb => Ok(t
            .bytes
            .chunks(4)
            .flat_map(|p| [p[2], p[1], p[0], p[3]])
            .collect()),
        f => Err(PassError::BadScene(format!(
            "the lighting measurement compares an 8-bit output; this pipeline's is {f:?}"
        ))),
    }
}

fn half4(bytes: &[u8]) -> Vec<[f32; 4]> {
    bytes
        .chunks(8)
        .map(|t| std::array::from_fn(|c| f16_to_f32(u16::from_le_bytes([t[2 * c], t[2 * c + 1]]))))
        .collect()
}

/// What a frame of a cone-traced pipeline left to compare: the G-buffer, the cone pass's
/// targets, the output and the knobs the reference shares with the cones.
pub struct LitFrame {
    width: u32,
    height: u32,
    albedo: Vec<u8>,
    position: Vec<f32>,
    normal: Vec<[f32; 4]>,
    occlusion: Vec<[f32; 4]>,
    indirect: Vec<[f32; 4]>,
    /// Size of the cone pass's targets (less than the G-buffer's when traced at a lower
    /// resolution).
    light_width: u32,
    light_height: u32,
    color: Vec<u8>,
    max_distance: f64,
    shadow_aperture: f64,
}

impl LitFrame {
    /// Reads the last frame of `r` back (fails when the pipeline has no `ConeTrace`).
    pub fn read(ctx: &GpuContext, r: &Renderer) -> Result<Self, PassError> {
        let (max_distance, shadow_aperture) = cone_knobs(r).ok_or_else(|| {
            PassError::BadScene("the pipeline has no ConeTrace pass to measure".into())
        })?;
        let normal_resource = r
            .pipeline
            .passes
            .iter()
            .find(|p| matches!(p.kind, PassKind::ConeTrace(_)))
            .and_then(|p| p.resource_of("normal"))
            .map(|i| r.pipeline.resources[i].name.clone())
            .unwrap_or_else(|| "gbuffer_normal".into());
        let albedo = read(ctx, r, "gbuffer_albedo")?;
        let occlusion = read(ctx, r, "occlusion")?;
        Ok(Self {
            light_width: occlusion.width,
            light_height: occlusion.height,
            width: albedo.width,
            height: albedo.height,
            albedo: albedo.bytes,
            position: read(ctx, r, "gbuffer_position")?.as_f32(),
            normal: float4(&read(ctx, r, &normal_resource)?),
            occlusion: half4(&occlusion.bytes),
            indirect: half4(&read(ctx, r, "indirect")?.bytes),
            color: rgba8(read(ctx, r, &r.pipeline.resources[r.pipeline.output].name)?)?,
            max_distance,
            shadow_aperture,
        })
    }

    /// The cone targets' texel holding pixel `i` (the pixel itself at full resolution; at
    /// a lower one, the texel whose traced pixel is at or before it: the traced pixels are
    /// those at multiples of the ratio, so an even `stride` compares exactly them at half
    /// resolution).
    fn light_texel(&self, i: usize) -> (usize, bool) {
        let (x, y) = (i % self.width as usize, i / self.width as usize);
        // One ratio for both axes, rounded, as the cone pass computes it (`misc.w`): a
        // 161-pixel screen has 81 half-resolution texels, ratio 2.
        let ratio = (f64::from(self.width) / f64::from(self.light_width.max(1)))
            .round()
            .max(1.0) as usize;
        let (rx, ry) = (ratio, ratio);
        let lx = (x / rx).min(self.light_width as usize - 1);
        let ly = (y / ry).min(self.light_height as usize - 1);
        (
            ly * self.light_width as usize + lx,
            x % rx == 0 && y % ry == 0,
        )
    }

    fn relative_position(&self, i: usize) -> [f32; 3] {
        let p = &self.position[i * 4..i * 4 + 3];
        [p[0], p[1], p[2]]
    }
}

/// The Monte Carlo reference at every `stride`-th row and column of `frame` where something
/// was drawn, `samples` rays per term, the exact voxels of `scene`'s instances at the
/// levels the renderer chose for `camera`; `near` is [`LightingParams::near`].
pub fn monte_carlo_reference(
    frame: &LitFrame,
    scene: &Scene,
    camera: &Camera,
    near: f64,
    samples: u32,
    stride: u32,
) -> Vec<(usize, LightingSample)> {
    let params = LightingParams {
        max_distance: frame.max_distance,
        shadow_aperture: frame.shadow_aperture,
        near,
    };
    let (w, h) = (frame.width, frame.height);
    let mut instances = Vec::new();
    for o in &scene.objects {
        let max = o.asset.lods.len() as u32 - 1;
        for xf in &o.instances {
            let level = choose_level(o.lod, xf, camera, (w, h), max);
            instances.push(Instance {
                lod: &o.asset.lods[level as usize],
                object_to_world: *xf,
                faces: None,
            });
        }
    }
    let tracer = Tracer::new(&instances);
    let stride = stride.max(1) as usize;
    let picked: Vec<usize> = (0..h as usize)
        .step_by(stride)
        .flat_map(|y| {
            (0..w as usize)
                .step_by(stride)
                .map(move |x| y * w as usize + x)
        })
        .filter(|&i| frame.albedo[i * 4 + 3] > 0)
        .collect();
    picked
        .par_iter()
        .map(|&i| {
            let p = frame.relative_position(i).map(f64::from);
            let n = frame.normal[i];
            let nd = DVec3::new(n[0].into(), n[1].into(), n[2].into());
            let world = camera.position + DVec3::from(p);
            let sample = monte_carlo(&tracer, &scene.light, &params, world, nd, samples, i as u64);
            (i, sample)
        })
        .collect()
}

/// Compares `frame` with its Monte Carlo `reference` ([`monte_carlo_reference`] of the
/// same G-buffer: the reference does not depend on the cone knobs, so a sweep computes it
/// once), lighting the reference with `light` as the composite does.
pub fn compare(
    frame: &LitFrame,
    reference: &[(usize, LightingSample)],
    light: &ssbvb_voxel::shading::Light,
) -> LightingReport {
    let pixels: Vec<LitPixel> = reference
        .iter()
        .map(|&(i, reference)| {
            let (t, traced) = frame.light_texel(i);
            let gpu = LightingSample {
                ao: frame.occlusion[t][0],
                shadow: frame.occlusion[t][1],
                indirect: [
                    frame.indirect[t][0],
                    frame.indirect[t][1],
                    frame.indirect[t][2],
                ],
            };
            let a = &frame.albedo[i * 4..i * 4 + 3];
            let albedo_lin = [a[0], a[1], a[2]].map(|c| f32::from(c) / 255.0);
            let lit = Lit {
                ao: reference.ao,
                shadow: reference.shadow,
                indirect: reference.indirect,
            };
            let p = frame.relative_position(i);
            let n = frame.normal[i];
            let view = [-p[0], -p[1], -p[2]];
            let c = shade_lit(albedo_lin, [n[0], n[1], n[2]], view, light, &lit);
            let out = &frame.color[i * 4..i * 4 + 3];
            LitPixel {
                index: i,
                gpu,
                reference,
                color: ([out[0], out[1], out[2]], c.map(linear_to_srgb8)),
                traced,
            }
        })
        .collect();
    let n = pixels.len().max(1) as f64;
    let mean = |f: &dyn Fn(&LitPixel) -> f64| pixels.iter().map(f).sum::<f64>() / n;
    let traced = pixels.iter().filter(|p| p.traced).count().max(1) as f64;
    let traced_mean = |f: &dyn Fn(&LitPixel) -> f64| {
        pixels.iter().filter(|p| p.traced).map(f).sum::<f64>() / traced
    };
    let ao_mae = traced_mean(&|p| f64::from((p.gpu.ao - p.reference.ao).abs()));
    let ao_bias = traced_mean(&|p| f64::from(p.gpu.ao - p.reference.ao));
    let shadow_mae = traced_mean(&|p| f64::from((p.gpu.shadow - p.reference.shadow).abs()));
    let indirect_mae = traced_mean(&|p| {
        (0..3)
            .map(|k| f64::from((p.gpu.indirect[k] - p.reference.indirect[k]).abs()))
            .sum::<f64>()
            / 3.0
    });
    let lit_mae = mean(&|p| {
        (0..3)
            .map(|k| {
                let g = srgb_to_linear(f32::from(p.color.0[k]) / 255.0);
                let r = srgb_to_linear(f32::from(p.color.1[k]) / 255.0);
                f64::from((g - r).abs())
            })
            .sum::<f64>()
            / 3.0
    });
    let mse = mean(&|p| {
        (0..3)
            .map(|k| (f64::from(p.color.0[k]) - f64::from(p.color.1[k])).powi(2))
            .sum::<f64>()
            / 3.0
    });
    let lit_psnr = if mse > 0.0 {
        10.0 * (255.0f64 * 255.0 / mse).log10()
    } else {
        f64::INFINITY
    };
    LightingReport {
        pixels,
        ao_mae,
        ao_bias,
        shadow_mae,
        indirect_mae,
        lit_mae,
        lit_psnr,
    }
}

/// [`LitFrame::read`], [`monte_carlo_reference`] and [`compare`] in one: the last frame of
/// `r` (rendered from `scene` with `camera`) against the Monte Carlo reference.
pub fn lighting_error(
    ctx: &GpuContext,
    r: &Renderer,
    scene: &Scene,
    camera: &Camera,
    near: f64,
    samples: u32,
    stride: u32,
) -> Result<LightingReport, PassError> {
    let frame = LitFrame::read(ctx, r)?;
    let reference = monte_carlo_reference(&frame, scene, camera, near, samples, stride);
    Ok(compare(&frame, &reference, &scene.light))
}
