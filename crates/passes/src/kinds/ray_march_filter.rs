//! `ray_march_filter`: the voxel filter (`RayMarchFilter`; `shaders/ray_march_filter.wgsl`).
//!
//! A compute pass, one thread per pixel: from the empty-space prepass's entry point it
//! marches the sparse lookup of the pixel's instance with a hierarchical voxel DDA (empty
//! coarse blocks and non-resident 16³ pages are crossed in one step) to the first voxel, and
//! appends it to the SSBVB (`ssbvb`) with an atomic counter that is also the instance count
//! of the billboard pass's indirect draw (`billboard_draw`): slots `0..count` are valid.
//! The march follows the CPU reference's rules (`ssbvb_voxel::reference::dda`) in f32 (the
//! WGSL header says how it stays robust). With several visible instances a pixel walks the
//! hierarchy over their boxes (group 0 `instance_bvh`) and marches those it enters before
//! its best hit: its cost follows the instances its ray meets, and overlaps stay exact.
//!
//! With `unique_voxels` each (visible instance, voxel) is appended once, by the first pixel
//! to claim its instance's first key + voxel id in an open-addressing hash set of at least
//! twice the filter's pixels: its memory follows the screen, and a voxel spanning n pixels
//! is drawn once, not n times, which bounds the overdraw of a camera close to a surface (an
//! instance whose keys would pass 2³² − 1 is not deduplicated).
//!
//! [`RayMarchFilter`]'s [`PassNode::counters`] are a few global atomics per ray with no
//! workgroup reduction, whose barriers cost the software adapter more (docs/benchmarks.md).
//! `clear_draw` resets the draw, `mark_tiles` flags the 16 × 16 tiles of the prepass with a
//! proxy, `list_tiles` lists them in screen order (so the SSBVB's order, which decides
//! exact depth ties between billboards, does not depend on thread timing) and makes the
//! list an indirect dispatch, and `main` runs a workgroup
//! of 16 × 16 per listed tile (cheaper than 8 × 8 on the software adapter; 256 invocations
//! is every adapter's minimum): a tile without a ray is not launched, which a software
//! adapter would otherwise run at nearly the cost of one with rays. A prepass and filter at
//! a fraction of the screen (`ScreenScaled`) cast one ray per texel centre.

use bytemuck::{Pod, Zeroable};
use ssbvb_gpu::requirements::max_compute_invocations_per_workgroup;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{MarchMode, RayMarchFilterParams};
use ssbvb_voxel::asset::PackedVoxel;

use crate::runtime::bindings::PassBindings;
use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::counters::{FrameCounters, check_steps_histogram, histogram_quantile};
use crate::runtime::recorder::Recorder;
use crate::runtime::pipelines::{VariantCache, compute_pipeline, pipeline_layout};
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::{CounterSource, PassNode};
use ssbvb_gpu::shaders;


/// Mirror of WGSL `VoxelSlot` (32 bytes): one SSBVB entry.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct VoxelSlot {
    /// The hit voxel: its cell, normal and colour as in its LOD's point cloud, and in
    /// place of texture coordinates (`uv`) the grid level of that LOD (the instance's, or
    /// under a GPU budget a coarser one where a page was not resident). The billboard
    /// passes size the voxel by it.
    pub voxel: PackedVoxel,
    /// Index of the instance in the frame's visible instances.
    pub instance: u32,
    /// `y * width + x` of the pixel whose ray found it.
    pub pixel: u32,
    /// World distance from the eye along the pixel's normalized ray to the entered face.
    pub t: f32,
    /// Entered face: 0..=2 the -X/-Y/-Z side (normal towards -axis), 3..=5 the +X/+Y/+Z
    /// side.
    pub face: u32,
}

impl VoxelSlot {
    /// The object-space unit normal of the entered face.
    pub fn face_normal(&self) -> [f32; 3] {
        let mut n = [0.0; 3];
        n[(self.face % 3) as usize] = if self.face >= 3 { 1.0 } else { -1.0 };
        n
    }
}

/// Mirror of the indirect draw arguments in `billboard_draw`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct DrawArgs {
    /// Vertices per billboard (4: a triangle strip).
    pub vertex_count: u32,
    /// Filled SSBVB slots.
    pub instance_count: u32,
    /// Always 0.
    pub first_vertex: u32,
    /// Always 0.
    pub first_instance: u32,
}

/// The compiled filter.
pub struct RayMarchFilter {
    clear: wgpu::ComputePipeline,
    /// Flags the tiles with a proxy (`mark_tiles`).
    mark_tiles: wgpu::ComputePipeline,
    /// Lists them in screen order and writes `main`'s indirect dispatch (`list_tiles`),
    /// with its own bindings.
    list_tiles: wgpu::ComputePipeline,
    list_bindings: PassBindings,
    /// `main`'s indirect dispatch arguments.
    dispatch: wgpu::Buffer,
    /// `main`, one pipeline per variant a frame has needed.
    mains: MainPipelines,
    /// Whether the last recorded frame counted.
    counted: bool,
    bindings: PassBindings,
    unique_voxels: bool,
    /// The frame's counters and, with `unique_voxels`, the per-instance first keys and
    /// the claim table (the table follows the filter's size, the keys grow with the
    /// visible instances).
    words: FilterWords,
}

/// Words of the counter buffer: rays, (low, high) sums of steps, boxes, marches and
/// lookup-node words read, then the steps-per-ray histogram (constants `C_*` in the WGSL).
pub(crate) const COUNTER_WORDS: usize = HISTOGRAM_WORD + crate::runtime::counters::STEP_BINS;

/// The first word of the histogram (`C_HISTOGRAM`).
const HISTOGRAM_WORD: usize = 9;

/// What the filter binds itself: one buffer of words (`FilterWords`), so that the
/// filter fits WebGPU's default 8 storage buffers per stage with the scene's and its slots;
/// and `main`'s indirect dispatch arguments, which only `list_tiles` binds (a dispatch may
/// not bind the buffer it reads its arguments from).
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "filter_words",
        kind: OwnKind::StorageReadWrite,
    },
    OwnBinding {
        name: "filter_dispatch",
        kind: OwnKind::StorageReadWrite,
    },
];

/// Group-1 bindings of `clear_draw`, `mark_tiles` and `main`: the slots and the words.
const MAIN_BINDINGS: [u32; 4] = [0, 1, 2, 3];
/// Group-1 bindings of `list_tiles`: the prepass (for its size), the words and the
/// arguments.
const LIST_BINDINGS: [u32; 3] = [0, 3, 4];

/// The word holding where the tile words start (`TILE_AT` in the WGSL).
const TILE_AT: u64 = COUNTER_WORDS as u64;
/// The first word of the claim header (`CLAIM_HEADER`).
const CLAIM_HEADER: u64 = TILE_AT + 1;

/// Texels per side of `main`'s tiles, its workgroup (`TILE` and `@workgroup_size(16, 16)`
/// in the WGSL).
pub const TILE: u32 = 16;

/// The tiles of `main` over a `w` × `h` prepass.
pub fn tile_count(w: u32, h: u32) -> u64 {
    u64::from(w.div_ceil(TILE)) * u64::from(h.div_ceil(TILE))
}

/// The filter's own words: the frame's counters (`COUNTER_WORDS`), then (`TILE_AT` in the
/// WGSL) where the tile words start, then (`CLAIM_HEADER`) where the claim table starts and
/// its size − 1, the first key of each of up to `key_capacity` visible instances, the claim
/// table, and the tile words: the count of listed tiles, a flag per tile, the list.
struct FilterWords {
    buffer: wgpu::Buffer,
    key_capacity: u64,
    table_words: u64,
    tiles: u64,
}

/// Marks an instance whose keys do not fit 32 bits (`NO_DEDUP` in the WGSL).
const NO_DEDUP: u32 = u32::MAX;

impl FilterWords {
    /// `table_words` must be a power of two (the shader masks the hash with it).
    fn new(ctx: &GpuContext, table_words: u64, key_capacity: u64, tiles: u64) -> Self {
        debug_assert!(table_words.is_power_of_two());
        let words = Self::words(table_words, key_capacity, tiles);
        Self {
            buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("filter words"),
                size: words * 4,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            key_capacity,
            table_words,
            tiles,
        }
    }

    /// Words of the whole buffer.
    fn words(table_words: u64, key_capacity: u64, tiles: u64) -> u64 {
        Self::table_start(key_capacity) + table_words + 1 + 2 * tiles
    }

    /// The first word of the claim table.
    fn table_start(key_capacity: u64) -> u64 {
        CLAIM_HEADER + 2 + key_capacity
    }

    /// The first tile word (the count of listed tiles).
    fn tiles_start(&self) -> u64 {
        Self::table_start(self.key_capacity) + self.table_words
    }

    /// The header and the first keys, as written before a frame.
    fn header(&self, keys: &[u32]) -> Vec<u32> {
        let start = Self::table_start(self.key_capacity) as u32;
        [self.tiles_start() as u32, start, self.table_words as u32 - 1]
            .into_iter()
            .chain(keys.iter().copied())
            .collect()
    }
}

/// Words of the claim table for a filter of `pixels` texels: the next power of two of
/// twice that, so the table is at most half full (every pixel claims at most one key).
pub fn claim_table_words(pixels: u64) -> u64 {
    (2 * pixels).max(16).next_power_of_two()
}

/// The first key of each visible instance whose levels hold `voxels` voxels: running sums,
/// and `u32::MAX` (no deduplication) for an instance whose keys would not all be below
/// `u32::MAX`.
pub fn claim_offsets(voxels: impl IntoIterator<Item = u64>) -> Vec<u32> {
    let mut next = 0u64;
    voxels
        .into_iter()
        .map(|n| {
            // Keys first..first + n - 1 must stay below u32::MAX (stored as key + 1).
            if n == 0 {
                0
            } else if next + n <= u32::MAX as u64 {
                let first = next as u32;
                next += n;
                first
            } else {
                NO_DEDUP
            }
        })
        .collect()
}

/// What a frame needs of `main`, as WGSL overrides: code a frame does not need is left out
/// of its pipeline (the software adapter runs the filter faster without the
/// instance-hierarchy walk; docs/benchmarks.md, "The crowd's walk, taken apart"). Each is on whenever the frame might need
/// it, so a variant is never chosen that draws a frame wrongly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MainVariant {
    /// Count the frame's work (`COUNT_WORK`: a report reads it,
    /// [`crate::Renderer::set_counting`]).
    pub count_work: bool,
    /// More than one instance is visible (`SEVERAL_INSTANCES`: the hierarchy walk).
    pub several_instances: bool,
    /// The scene is uploaded under a GPU budget (`PAGED`: pages and their feedback).
    pub paged: bool,
}

impl MainVariant {
    /// The WGSL overrides of this variant.
    pub fn constants(self) -> [(&'static str, f64); 3] {
        [
            ("COUNT_WORK", flag(self.count_work)),
            ("SEVERAL_INSTANCES", flag(self.several_instances)),
            ("PAGED", flag(self.paged)),
        ]
    }
}

fn flag(on: bool) -> f64 {
    if on { 1.0 } else { 0.0 }
}

/// `main`'s pipelines, compiled when a frame first needs each variant.
struct MainPipelines {
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    /// The pass's own overrides (from its parameters).
    constants: [(&'static str, f64); 6],
    label: String,
    built: VariantCache<MainVariant, wgpu::ComputePipeline>,
}

impl MainPipelines {
    fn get(
        &mut self,
        ctx: &GpuContext,
        variant: MainVariant,
    ) -> Result<&wgpu::ComputePipeline, PassError> {
        let (layout, module, label) = (&self.layout, &self.module, &self.label);
        let constants = &self.constants;
        self.built.get_or_build(variant, || {
            let mut constants = constants.to_vec();
            constants.extend(variant.constants());
            ctx.validated(&format!("{label} ({variant:?})"), |d| {
                compute_pipeline(d, layout, module, "main", &constants)
            })
            .map_err(PassError::from)
        })
    }
}

impl PassImpl for RayMarchFilter {
    type Params = RayMarchFilterParams;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "ray_march_filter.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    // Its output is the billboards' indirect draw; 16×16 threads per workgroup.
    const NEEDS: KindNeeds = KindNeeds {
        limit: Some(max_compute_invocations_per_workgroup(256)),
        ..KindNeeds::new(wgpu::DownlevelFlags::INDIRECT_EXECUTION, 3)
    };

    /// Compiles `clear_draw`; `main` is compiled per [`MainVariant`] when a frame first
    /// needs it. `max_steps` becomes the WGSL override `MAX_STEPS`, `march: Fast` the
    /// override `FAST_MARCH`.
    fn new(init: &PassInit<'_>, params: &RayMarchFilterParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let RayMarchFilterParams {
            max_steps,
            unique_voxels,
            march,
            ..
        } = *params;
        let module = ctx.shader(
            "ray_march_filter.wgsl",
            &shaders::source_for("ray_march_filter.wgsl", &scene.bindings)?,
        )?;
        let label = format!("pass `{}`: ray_march_filter pipelines", pass.name);
        let constants = [
            ("MAX_STEPS", f64::from(max_steps)),
            ("UNIQUE_VOXELS", flag(unique_voxels)),
            ("FAST_MARCH", flag(march == MarchMode::Fast)),
            ("TILE_AT", TILE_AT as f64),
            ("CLAIM_HEADER", CLAIM_HEADER as f64),
            (
                "MAX_GRID",
                f64::from(ctx.device.limits().max_compute_workgroups_per_dimension),
            ),
        ];
        let (clear, mark_tiles, layout, bindings) = ctx.validated(&label, |d| {
            let bindings = PassBindings::used_only(ctx, pipeline, pass, OWN, Some(&MAIN_BINDINGS));
            let layout = pipeline_layout(d, "ray_march_filter", scene, Some(&bindings));
            let clear = compute_pipeline(d, &layout, &module, "clear_draw", &constants);
            let mark_tiles = compute_pipeline(d, &layout, &module, "mark_tiles", &constants);
            (clear, mark_tiles, layout, bindings)
        })?;
        let (list_tiles, list_bindings) = ctx.validated(&label, |d| {
            let bindings = PassBindings::used_only(ctx, pipeline, pass, OWN, Some(&LIST_BINDINGS));
            let layout = pipeline_layout(d, "ray_march_filter list", scene, Some(&bindings));
            let list = compute_pipeline(d, &layout, &module, "list_tiles", &constants);
            (list, bindings)
        })?;
        let dispatch = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("filter dispatch arguments"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        let mains = MainPipelines {
            module,
            layout,
            constants,
            label,
            built: VariantCache::default(),
        };
        // Without unique_voxels the shader never touches the claims: the smallest table.
        // The tiles are sized by the first frame.
        let words = FilterWords::new(ctx, 16, 4, 0);
        Ok(Self {
            clear,
            mark_tiles,
            list_tiles,
            list_bindings,
            dispatch,
            mains,
            counted: false,
            bindings,
            unique_voxels,
            words,
        })
    }
}

impl PassNode for RayMarchFilter {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        self.prepare_words(rec, encoder)?;
        let entry = &rec.texture("entry").texture;
        let (w, h) = (entry.width(), entry.height());
        let bind_group = self
            .bindings
            .bind_group(rec, &[("filter_words", self.words.buffer.as_entire_binding())])?;
        let list_group = self.list_bindings.bind_group(
            rec,
            &[
                ("filter_words", self.words.buffer.as_entire_binding()),
                ("filter_dispatch", self.dispatch.as_entire_binding()),
            ],
        )?;
        self.counted = rec.counting;
        let variant = MainVariant {
            count_work: self.counted,
            several_instances: rec.scene.visible.len() > 1,
            paged: rec.scene.streaming.is_some(),
        };
        let main = self.mains.get(rec.gpu, variant)?;
        if self.counted {
            encoder.clear_buffer(&self.words.buffer, 0, Some(COUNTER_WORDS as u64 * 4));
        }
        let timestamps = rec.compute_timestamps();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&rec.pass.name),
            timestamp_writes: timestamps,
        });
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        pass.set_bind_group(1, &bind_group, &[]);
        pass.set_pipeline(&self.clear);
        pass.dispatch_workgroups(1, 1, 1);
        // wgpu orders the dispatches: the draw arguments are written before `main` counts,
        // the tiles flagged before they are listed, and listed before `main` reads them.
        pass.set_pipeline(&self.mark_tiles);
        pass.dispatch_workgroups(w.div_ceil(TILE), h.div_ceil(TILE), 1);
        pass.set_bind_group(1, &list_group, &[]);
        pass.set_pipeline(&self.list_tiles);
        pass.dispatch_workgroups(1, 1, 1);
        pass.set_bind_group(1, &bind_group, &[]);
        pass.set_pipeline(main);
        pass.dispatch_workgroups_indirect(&self.dispatch, 0);
        Ok(())
    }

    fn fill_count(&self, frame: &CounterSource<'_>) -> Result<Option<u32>, PassError> {
        let Some(draw) = frame.buffer("billboard_draw") else {
            return Ok(None);
        };
        let args = parse_draw_args(&frame.gpu.read_buffer(draw)?)?;
        Ok(Some(args.instance_count))
    }

    fn counters(&self, frame: &CounterSource<'_>, out: &mut FrameCounters) -> Result<(), PassError> {
        out.billboards_drawn = self.fill_count(frame)?.map(u64::from);
        if !self.counted {
            return Ok(());
        }
        read_march_counters(frame.gpu, &self.words.buffer, out)?;
        let tiles = ssbvb_gpu::kernels::read_words(
            frame.gpu,
            &self.words.buffer,
            self.words.tiles_start(),
            1,
        )?;
        out.filter_tiles = tiles.first().map(|&t| u64::from(t));
        Ok(())
    }
}

impl RayMarchFilter {
    /// Sizes the words for the prepass's tiles and, with `unique_voxels`, lays out the
    /// keys of the visible instances and sizes the claim table for the filter's texels
    /// (reallocated when that changes; the offsets grow by half again when the visible
    /// instances outgrow them); uploads the header and records the clears of the tile
    /// count and flags and of the claim table.
    fn prepare_words(
        &mut self,
        rec: &Recorder<'_>,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), PassError> {
        let scene = rec.scene;
        let offsets = if self.unique_voxels {
            claim_offsets(
                scene
                    .visible
                    .iter()
                    .map(|v| scene.voxel_key_range(v.object, v.level)),
            )
        } else {
            Vec::new()
        };
        let entry = &rec.texture("entry").texture;
        let tiles = tile_count(entry.width(), entry.height());
        // Without unique_voxels the shader never touches the claims: the smallest table.
        let words = if self.unique_voxels {
            claim_table_words(entry.width() as u64 * entry.height() as u64)
        } else {
            16
        };
        let max = rec.gpu.device.limits().max_storage_buffer_binding_size;
        let instances = offsets.len().max(1) as u64;
        let bytes = FilterWords::words(words, instances + instances / 2, tiles) * 4;
        if bytes > max {
            return Err(PassError::TooLarge(format!(
                "the filter needs {bytes} bytes of words (claim table and tile list) for \
                 {}x{} pixels and {} instances; the device binds at most {max}: use a \
                 smaller screen or turn unique_voxels off",
                entry.width(),
                entry.height(),
                offsets.len()
            )));
        }
        let (table_fits, keys_fit) = (
            self.words.table_words == words && self.words.tiles == tiles,
            self.words.key_capacity >= instances,
        );
        if !table_fits || !keys_fit {
            let cap = if keys_fit {
                self.words.key_capacity
            } else {
                instances + instances / 2
            };
            self.words = FilterWords::new(rec.gpu, words, cap, tiles);
        }
        let header = self.words.header(&offsets);
        rec.gpu
            .queue
            .write_buffer(&self.words.buffer, TILE_AT * 4, bytemuck::cast_slice(&header));
        // The tile count and flags; the list is written before it is read.
        let tiles_at = self.words.tiles_start() * 4;
        encoder.clear_buffer(&self.words.buffer, tiles_at, Some((1 + tiles) * 4));
        if self.unique_voxels {
            let table = FilterWords::table_start(self.words.key_capacity) * 4;
            encoder.clear_buffer(&self.words.buffer, table, Some(words * 4));
        }
        Ok(())
    }
}

/// Reads the march counters at the start of `buffer` (`COUNTER_WORDS` words, the layout
/// of `filter_march.inc.wgsl`) into `out`: rays, steps (mean and p99 of the histogram),
/// boxes and instances per ray, lookup words per step; checked for consistency.
pub(crate) fn read_march_counters(
    gpu: &GpuContext,
    buffer: &wgpu::Buffer,
    out: &mut FrameCounters,
) -> Result<(), PassError> {
        let words = ssbvb_gpu::kernels::read_words(
            gpu,
            buffer,
            0,
            COUNTER_WORDS as u64,
        )?;
        if words.len() < COUNTER_WORDS {
            return Err(PassError::BadScene("filter counters readback is short".into()));
        }
        let wide = |i: usize| words[i] as u64 | (words[i + 1] as u64) << 32;
        let rays = words[0] as u64;
        let per_ray = |sum: u64| (rays > 0).then(|| sum as f64 / rays as f64);
        out.filter_rays = Some(rays);
        out.march_steps_mean = per_ray(wide(1));
        out.instance_boxes_per_ray = per_ray(wide(3));
        out.instances_marched_per_ray = per_ray(wide(5));
        let histogram = &words[HISTOGRAM_WORD..COUNTER_WORDS];
        let steps = wide(1);
        check_steps_histogram(rays, steps, histogram).map_err(PassError::InconsistentCounters)?;
        // Every ray marches its prepass instance at least.
        if wide(5) < rays {
            return Err(PassError::InconsistentCounters(format!(
                "{} instance marches counted for {rays} rays",
                wide(5)
            )));
        }
        out.march_steps_p99 = histogram_quantile(histogram, 0.99);
    out.node_words_per_step = (steps > 0).then(|| wide(7) as f64 / steps as f64);
    Ok(())
}

/// The indirect draw the filter wrote into `billboard_draw` (its first 16 bytes, read
/// back); the SSBVB fill count is its `instance_count`.
pub fn parse_draw_args(bytes: &[u8]) -> Result<DrawArgs, PassError> {
    let args: &[DrawArgs] = bytemuck::try_cast_slice(&bytes[..16.min(bytes.len())])
        .map_err(|e| PassError::BadScene(format!("billboard_draw readback: {e}")))?;
    args.first()
        .copied()
        .ok_or_else(|| PassError::BadScene("billboard_draw readback is empty".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn claim_table_is_a_power_of_two_at_least_twice_the_pixels() {
        for pixels in [0u64, 1, 7, 4800, 640 * 480, 1280 * 720, 3840 * 2160] {
            let w = claim_table_words(pixels);
            assert!(w.is_power_of_two() && w >= 2 * pixels && w >= 16, "{pixels}: {w}");
            assert!(w < 4 * pixels.max(8), "{pixels}: {w} is more than needed");
        }
    }

    #[test]
    fn claim_offsets_are_running_sums_until_keys_pass_32_bits() {
        // An instance without voxels claims nothing (its offset does not matter).
        assert_eq!(claim_offsets([10, 0, 5, 7]), vec![0, 0, 10, 15]);
        let big = u32::MAX as u64 / 2;
        // The third instance's keys would reach u32::MAX: it is not deduplicated, and a
        // later small one that still fits keeps its range.
        assert_eq!(
            claim_offsets([big, big, 10, 1]),
            vec![0, big as u32, NO_DEDUP, 2 * big as u32]
        );
        assert!(claim_offsets([]).is_empty());
    }
}
