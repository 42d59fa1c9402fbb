//! `empty_space_compute`: the empty-space prepass in compute (`EmptySpaceCompute`;
//! `shaders/empty_space_compute.wgsl`), for adapters whose raster units are slow (on the
//! NVIDIA H200 of `docs/benchmarks.md` the rasterized prepass is a large share of the
//! frame).
//!
//! It writes what [`crate::kinds::empty_space`] rasterizes, into `entry` as a storage
//! texture: per texel the object-space point where the texel-centre ray enters the nearest
//! proxy (the camera for a back face, and the camera of an instance whose proxy holds it
//! where no proxy is drawn), and the instance index + 1. The proxies are rasterized in
//! software, one thread per triangle: near clipping, watertight edge functions, the
//! nearest depth by `atomicMax`, then the lowest triangle at that depth, then a resolve
//! per texel. Triangles whose rectangle is large get a workgroup each, listed by the
//! first step and dispatched indirectly. Core 32-bit atomics only, so the form runs within
//! WebGPU's limits.
//!
//! Its own buffer holds, per frame: a header and the runs of triangles (one per visible
//! instance with a proxy, written here from the CPU's visible list); two words per texel;
//! then the large triangles' count and list.

use ssbvb_gpu::scene::VisibleInstance;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::EmptySpaceComputeParams;

use crate::error::PassError;
use crate::runtime::bindings::PassBindings;
use crate::runtime::node::PassNode;
use crate::runtime::pipelines::{compute_pipeline, pipeline_layout};
use crate::runtime::recorder::Recorder;
use crate::runtime::registry::{KindNeeds, OwnBinding, OwnKind, PassImpl, PassInit};
use ssbvb_gpu::shaders;

/// What the pass binds itself: the scene's proxy meshes, its words, and the large
/// triangles' indirect dispatch (bound only by `large_args`).
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "proxy_vertices",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "proxy_indices",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "prepass_words",
        kind: OwnKind::StorageReadWrite,
    },
    OwnBinding {
        name: "prepass_dispatch",
        kind: OwnKind::StorageReadWrite,
    },
];

/// Group-1 bindings of the raster steps and the resolve: `entry`, the proxies, the words.
const RASTER_BINDINGS: [u32; 4] = [0, 1, 2, 3];
/// Group-1 bindings of `large_args`: `entry` (its size), the words and the dispatch.
const ARGS_BINDINGS: [u32; 3] = [0, 3, 4];

/// Words per run (after the four of the header, `H_*` in the WGSL).
const RUN_WORDS: u64 = 4;
/// A run's instance word flags an instance that draws its back faces.
const BACK_FACES: u32 = 0x8000_0000;
/// Threads per workgroup of the per-triangle steps.
const GROUP: u64 = 64;
/// Bytes of the large triangles' dispatch arguments: two grids of three `u32`.
const DISPATCH_BYTES: u64 = 24;
/// Texels a side of the resolve's workgroups.
const RESOLVE_TILE: u32 = 8;

/// Texels of a triangle's rectangle above which it gets a workgroup of its own (WGSL
/// override `LARGE_PIXELS`), unless the pass names it (`large_pixels`). On a CPU adapter
/// a workgroup is a task with its own cost, and llvmpipe ran the bunny's proxy fastest
/// with (almost) none (docs/benchmarks.md); on a GPU one thread walking thousands of
/// texels holds its whole wave back, so there the rectangle of a few small triangles is
/// the limit (not yet measured on one).
fn large_pixels(ctx: &GpuContext, param: Option<u32>) -> u32 {
    if let Some(n) = param {
        n
    } else if ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
        4096
    } else {
        256
    }
}

/// The frame's triangles: the header and the runs, and how many triangles.
fn frame_runs(visible: &[VisibleInstance]) -> (Vec<u32>, u64) {
    let mut runs = Vec::new();
    let mut triangles = 0u64;
    let mut fill = 0u32;
    for (i, v) in visible.iter().enumerate() {
        if v.camera_inside {
            fill = i as u32 + 1;
        }
        let count = u64::from(v.proxy.index_count / 3);
        if count == 0 {
            continue;
        }
        let tagged = i as u32 | if v.back_faces { BACK_FACES } else { 0 };
        runs.extend([
            triangles as u32,
            v.proxy.first_index,
            v.proxy.base_vertex as u32,
            tagged,
        ]);
        triangles += count;
    }
    let run_count = runs.len() as u64 / RUN_WORDS;
    let texels_at = 4 + runs.len() as u32;
    let mut words = vec![run_count as u32, triangles as u32, fill, texels_at];
    words.extend(runs);
    (words, triangles)
}

/// A dispatch of `groups` workgroups within `max` a dimension.
fn grid(groups: u64, max: u32) -> (u32, u32) {
    let x = groups.min(u64::from(max)).max(1);
    (x as u32, groups.div_ceil(x) as u32)
}

/// The compiled prepass.
pub struct EmptySpaceCompute {
    raster: wgpu::ComputePipeline,
    large_args: wgpu::ComputePipeline,
    large_triangles: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    bindings: PassBindings,
    args_bindings: PassBindings,
    /// The large triangles' indirect dispatch.
    dispatch: wgpu::Buffer,
    /// The header and runs, the per-texel words and the large list, and the count of
    /// words.
    words: Option<(wgpu::Buffer, u64)>,
}

impl PassImpl for EmptySpaceCompute {
    type Params = EmptySpaceComputeParams;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "empty_space_compute.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    // The large triangles' dispatch is indirect; the raster steps bind three storage
    // buffers (the proxy's two and the words).
    const NEEDS: KindNeeds = KindNeeds::new(wgpu::DownlevelFlags::INDIRECT_EXECUTION, 3);

    fn new(init: &PassInit<'_>, params: &EmptySpaceComputeParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let module = ctx.shader(
            Self::SHADER,
            &shaders::source_for(Self::SHADER, &scene.bindings)?,
        )?;
        let label = format!("pass `{}`: empty_space_compute pipelines", pass.name);
        let bindings = PassBindings::used_only(ctx, pipeline, pass, OWN, Some(&RASTER_BINDINGS));
        let args_bindings = PassBindings::used_only(ctx, pipeline, pass, OWN, Some(&ARGS_BINDINGS));
        let large = f64::from(large_pixels(ctx, params.large_pixels));
        // One pipeline each for `raster` and `large` runs both steps (see the WGSL), so
        // that both compute the same depths.
        let [raster, large_triangles, resolve] = ctx.validated(&label, |d| {
            let layout = pipeline_layout(d, &label, scene, Some(&bindings));
            let constants = [("LARGE_PIXELS", large)];
            ["raster", "large", "resolve"]
                .map(|entry| compute_pipeline(d, &layout, &module, entry, &constants))
        })?;
        let large_args = ctx.validated(&label, |d| {
            let layout = pipeline_layout(d, &label, scene, Some(&args_bindings));
            compute_pipeline(d, &layout, &module, "large_args", &[])
        })?;
        let dispatch = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("prepass dispatch arguments"),
            // Two grids: the large triangles' steps 1 and 2.
            size: DISPATCH_BYTES,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        Ok(Self {
            raster,
            large_args,
            large_triangles,
            resolve,
            bindings,
            args_bindings,
            dispatch,
            words: None,
        })
    }
}

/// `slot`'s buffer of at least `count` words (made, or remade larger; out of memory is an
/// error naming the size: the texels' words are 8 bytes a texel, 66 MB at 4K).
fn words_buffer(
    ctx: &GpuContext,
    slot: &mut Option<(wgpu::Buffer, u64)>,
    label: &'static str,
    count: u64,
) -> Result<wgpu::Buffer, PassError> {
    if slot.as_ref().is_none_or(|(_, n)| *n < count) {
        let buffer = ctx.checked_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: (count * 4).max(16),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })?;
        *slot = Some((buffer, count));
    }
    Ok(slot.as_ref().expect("made above").0.clone())
}

impl PassNode for EmptySpaceCompute {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let entry = &rec.texture("entry").texture;
        let (w, h) = (entry.width(), entry.height());
        let texels = u64::from(w) * u64::from(h);
        let (header, triangles) = frame_runs(&rec.scene.visible);
        // The header and runs, two words a texel, the large triangles' count, and room for
        // every triangle.
        let texels_at = header.len() as u64;
        let bytes = 4 * (texels_at + 2 * texels + 1 + triangles);
        let max = rec.gpu.device.limits().max_storage_buffer_binding_size;
        // A key holds a triangle's index in 31 bits (its facing in the 32nd).
        if bytes > max || triangles >= 1 << 31 {
            return Err(PassError::TooLarge(format!(
                "pass `{}` (EmptySpaceCompute) needs {bytes} bytes of words for {w}x{h}                  texels and {triangles} proxy triangles; the device binds at most {max}:                  use a smaller screen or the rasterized prepass (EmptySpacePrepass)",
                rec.pass.name
            )));
        }
        let words = words_buffer(
            rec.gpu,
            &mut self.words,
            "prepass words",
            texels_at + 2 * texels + 1 + triangles,
        )?;
        rec.gpu
            .queue
            .write_buffer(&words, 0, bytemuck::cast_slice(&header));
        encoder.clear_buffer(&words, texels_at * 4, Some((2 * texels + 1) * 4));
        let scene = rec.scene;
        let own = [
            (
                "proxy_vertices",
                scene.proxy_vertices.as_entire_binding(),
            ),
            ("proxy_indices", scene.proxy_indices.as_entire_binding()),
            ("prepass_words", words.as_entire_binding()),
            ("prepass_dispatch", self.dispatch.as_entire_binding()),
        ];
        let bind_group = self.bindings.bind_group(rec, &own)?;
        let args_group = self.args_bindings.bind_group(rec, &own)?;
        let max = rec.gpu.device.limits().max_compute_workgroups_per_dimension;
        let (gx, gy) = grid(triangles.div_ceil(GROUP), max);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&rec.pass.name),
            timestamp_writes: rec.compute_timestamps(),
        });
        pass.set_bind_group(0, &scene.bind_group, &[]);
        // wgpu orders the dispatches of a pass: every depth is in before an index is
        // offered, and every index before the resolve reads it.
        if triangles > 0 {
            // Step 1 with one layer of workgroups, step 2 with two (the first idle).
            pass.set_bind_group(1, &bind_group, &[]);
            pass.set_pipeline(&self.raster);
            pass.dispatch_workgroups(gx, gy, 1);
            pass.set_bind_group(1, &args_group, &[]);
            pass.set_pipeline(&self.large_args);
            pass.dispatch_workgroups(1, 1, 1);
            pass.set_bind_group(1, &bind_group, &[]);
            pass.set_pipeline(&self.large_triangles);
            pass.dispatch_workgroups_indirect(&self.dispatch, 0);
            pass.set_pipeline(&self.raster);
            pass.dispatch_workgroups(gx, gy, 2);
            pass.set_pipeline(&self.large_triangles);
            pass.dispatch_workgroups_indirect(&self.dispatch, DISPATCH_BYTES / 2);
        }
        pass.set_bind_group(1, &bind_group, &[]);
        pass.set_pipeline(&self.resolve);
        pass.dispatch_workgroups(w.div_ceil(RESOLVE_TILE), h.div_ceil(RESOLVE_TILE), 1);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ssbvb_gpu::scene::ProxyRange;

    fn instance(index_count: u32, camera_inside: bool, back_faces: bool) -> VisibleInstance {
        VisibleInstance {
            scene_index: 0,
            object: 0,
            level: 0,
            proxy: ProxyRange {
                first_index: 36,
                index_count,
                base_vertex: 8,
            },
            proxy_level: 0,
            camera_inside,
            back_faces,
        }
    }

    #[test]
    fn runs_number_the_triangles_of_the_instances_with_a_proxy() {
        let visible = [
            instance(36, false, false),
            instance(0, true, true),
            instance(12, true, true),
            instance(0, false, false),
        ];
        let (words, triangles) = frame_runs(&visible);
        assert_eq!(triangles, 16);
        // Two runs; the last instance holding the camera fills; the texels after the runs.
        assert_eq!(&words[..4], &[2, 16, 3, 12]);
        assert_eq!(&words[4..8], &[0, 36, 8, 0]);
        assert_eq!(&words[8..12], &[12, 36, 8, 2 | BACK_FACES]);
        assert_eq!(words.len(), 12);
        assert_eq!(frame_runs(&[]).0, [0, 0, 0, 4]);
    }

    #[test]
    fn grids_stay_within_the_dimension_limit() {
        assert_eq!(grid(0, 65535), (1, 0));
        assert_eq!(grid(10, 65535), (10, 1));
        assert_eq!(grid(65536, 65535), (65535, 2));
        assert_eq!(grid(200_000, 65535), (65535, 4));
    }
}
