//! The RastaVox surface model built on the GPU (`shaders/surface_build.wgsl`):
//! from a LOD level's point cloud, the boundary voxels with their face masks (one thread
//! per voxel, neighbours by binary search in the Morton-sorted points, an atomic output
//! slot as in the paper), a radix sort of their Morton keys ([`GpuRadixSort`]), then per
//! coarser LOD: run starts by a prefix scan and one thread per run OR-merging face masks and
//! averaging colours and normals. Chunk ranges and tight bounds are found on the GPU and read
//! back (a few words per chunk and level), so drawing needs no further readback.
//!
//! The result equals [`SurfaceModel::extract`] (the CPU oracle) voxel for voxel — masks,
//! colours, ranges, bounds — and normals up to one octahedral step (GPU `sqrt` and division
//! round differently); the GPU tests check this on the shared models.

use web_time::Instant;

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_voxel::asset::LodLevel;
use ssbvb_voxel::surface::{
    ATTRIBUTE_BYTES, MAX_CHUNK_LOG2, SURFACE_VOXEL_BYTES, SurfaceLevel, SurfaceModel, SurfaceVoxel,
};
use ssbvb_voxel::svo::morton_decode;

use ssbvb_gpu::ResourceError;
use ssbvb_gpu::kernels::radix_sort::{GpuRadixSort, SortBuffers};
use ssbvb_gpu::kernels::scan::GpuScan;
use ssbvb_gpu::kernels::{
    Bind, KernelBindGroups, Kernels, WORKGROUP, read_words, storage, storage_init, uniform,
};

/// One LOD of a GPU surface model.
pub struct GpuSurfaceLevel {
    /// Surface voxels ([`SurfaceVoxel`] words), chunk-major.
    pub surface: wgpu::Buffer,
    /// Two words per voxel: colour, normal.
    pub attrs: wgpu::Buffer,
    /// Voxels.
    pub count: u32,
    /// Per chunk: first voxel and count.
    pub ranges: Vec<[u32; 2]>,
}

/// Build times (host wall clock, each step waited for), the paper's Table 2 columns.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BuildTimes {
    /// Extraction, sort and gather of the finest level (with chunk ranges and bounds).
    pub base_seconds: f64,
    /// Every coarser level.
    pub lod_seconds: f64,
}

/// A surface model on the GPU ([`SurfaceModel`]'s layout).
pub struct GpuSurface {
    /// Grid level of the finest surface.
    pub level: u32,
    /// log2 of the chunk edge in finest cells.
    pub chunk_log2: u32,
    /// Chunk coordinates, Morton order.
    pub chunks: Vec<[u32; 3]>,
    /// Tight bounds per chunk in finest cells (min, max + 1).
    pub bounds: Vec<[[u32; 3]; 2]>,
    /// `levels[k]`: LOD k (grid level `level - k`).
    pub levels: Vec<GpuSurfaceLevel>,
    /// How long the build took.
    pub times: BuildTimes,
}

impl GpuSurface {
    /// Surface voxels at the finest level.
    pub fn surface_voxels(&self) -> u64 {
        self.levels.first().map_or(0, |l| u64::from(l.count))
    }

    /// Bytes of the voxel and attribute buffers of every level.
    pub fn bytes(&self) -> u64 {
        let voxels: u64 = self.levels.iter().map(|l| u64::from(l.count)).sum();
        voxels * (SURFACE_VOXEL_BYTES + ATTRIBUTE_BYTES)
    }

    /// Reads the whole model back (tests; the cross-check against the CPU build).
    pub fn read_back(&self, ctx: &GpuContext) -> Result<SurfaceModel, ResourceError> {
        let mut levels = Vec::new();
        for l in &self.levels {
            let n = u64::from(l.count);
            let voxels = read_words(ctx, &l.surface, 0, n)?;
            let attrs = read_words(ctx, &l.attrs, 0, 2 * n)?;
            levels.push(SurfaceLevel {
                voxels: voxels.into_iter().map(SurfaceVoxel).collect(),
                colors: attrs.iter().step_by(2).copied().collect(),
                normals: attrs.iter().skip(1).step_by(2).copied().collect(),
                ranges: l.ranges.clone(),
            });
        }
        Ok(SurfaceModel {
            level: self.level,
            chunk_log2: self.chunk_log2,
            chunks: self.chunks.clone(),
            bounds: self.bounds.clone(),
            levels,
        })
    }
}

/// The buffers of one kernel dispatch (`None`: a binding the kernel does not use, bound
/// to a small unused buffer because a bind group needs every entry).
#[derive(Default)]
struct Binds<'a> {
    key: Option<&'a SortBuffers>,
    val: Option<&'a wgpu::Buffer>,
    next: Option<&'a SortBuffers>,
    flags: Option<&'a wgpu::Buffer>,
    counters: Option<&'a wgpu::Buffer>,
    surface_in: Option<&'a wgpu::Buffer>,
    attrs_in: Option<&'a wgpu::Buffer>,
    surface_out: Option<&'a wgpu::Buffer>,
    attrs_out: Option<&'a wgpu::Buffer>,
}

/// The compiled build.
pub struct SurfaceBuilder {
    kernels: Kernels,
    sort: GpuRadixSort,
}

/// Workgroups for one thread per item.
fn groups(n: u32) -> u32 {
    n.div_ceil(WORKGROUP)
}

impl SurfaceBuilder {
    /// Compiles the kernels.
    pub fn new(ctx: &GpuContext) -> Result<Self, ResourceError> {
        use Bind::*;
        let mut binds = vec![Uniform, Read];
        binds.extend([ReadWrite; 7]);
        binds.extend([Read, Read, ReadWrite, ReadWrite]);
        Ok(Self {
            kernels: Kernels::new(
                ctx,
                "surface_build.wgsl",
                &binds,
                &[
                    "extract",
                    "gather_finest",
                    "run_flags",
                    "run_starts",
                    "merge",
                    "merge_keys",
                    "chunk_starts",
                    "chunk_bounds",
                ],
            )?,
            sort: GpuRadixSort::new(ctx)?,
        })
    }

    /// Builds the surface model of `lod` on the GPU.
    pub fn build(&self, ctx: &GpuContext, lod: &LodLevel) -> Result<GpuSurface, ResourceError> {
        let t0 = Instant::now();
        let level = lod.level;
        let chunk_log2 = level.min(MAX_CHUNK_LOG2);
        let points = &lod.point_cloud.voxels;
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        let n = u32::try_from(points.len())
            .ok()
            .filter(|&n| u64::from(n) * 16 <= limit && level <= 16)
            .ok_or_else(|| {
                ResourceError::TooLarge(format!(
                    "RastaVox: level {level} has {} voxels ({} MiB of points), above the \
                     device's storage binding limit of {} MiB",
                    points.len(),
                    (points.len() * 16) >> 20,
                    limit >> 20
                ))
            })?;
        let mut model = GpuSurface {
            level,
            chunk_log2,
            chunks: Vec::new(),
            bounds: Vec::new(),
            levels: Vec::new(),
            times: BuildTimes::default(),
        };
        if n == 0 {
            return Ok(model);
        }
        let d = &ctx.device;
        let run = BuildRun {
            builder: self,
            ctx,
            level,
            chunk_log2,
            points: storage_init(
                d,
                "rastavox points",
                bytemuck::cast_slice(points.as_slice()),
            ),
            dummy_read: storage(d, "rastavox unused", 1),
            dummy_rw: storage(d, "rastavox unused", 1),
        };
        let mut a = SortBuffers::new(d, "rastavox keys", u64::from(n));
        let mut b = SortBuffers::new(d, "rastavox keys", u64::from(n));
        let m = run.extract(&a, n)?;
        if m == 0 {
            return Ok(model);
        }
        if run.sort(&a, &b, m) {
            std::mem::swap(&mut a, &mut b);
        }
        let flags = storage(d, "rastavox flags", u64::from(m));
        let (finest, local_bounds) = run.finest_level(&a, &flags, m)?;
        let chunks = finest.ranges.len() as u32;
        model.levels.push(finest);
        model.times.base_seconds = t0.elapsed().as_secs_f64();

        // Coarser levels: runs of children by scan, one thread per run.
        let t1 = Instant::now();
        for k in 0..chunk_log2 {
            let prev = model.levels.last().expect("the finest level");
            let next = run.coarser_level(prev, &a, &b, &flags, k)?;
            if next.ranges.len() as u32 != chunks {
                return Err(ResourceError::BadScene(format!(
                    "RastaVox build: LOD {} has {} chunks, the finest {chunks}",
                    k + 1,
                    next.ranges.len()
                )));
            }
            model.levels.push(next);
            std::mem::swap(&mut a, &mut b);
        }
        // The coarsest level holds one voxel per chunk: its keys are the chunk codes.
        let lo = read_words(ctx, &a.lo, 0, u64::from(chunks))?;
        let hi = read_words(ctx, &a.hi, 0, u64::from(chunks))?;
        for c in 0..chunks as usize {
            let code = u64::from(lo[c]) | u64::from(hi[c] & 0xff_ffff) << 32;
            let chunk = morton_decode(code);
            let origin = chunk.map(|x| x << chunk_log2);
            let lb = &local_bounds[6 * c..6 * c + 6];
            model.chunks.push(chunk);
            model.bounds.push([
                [0, 1, 2].map(|i| origin[i] + lb[i]),
                [0, 1, 2].map(|i| origin[i] + lb[3 + i]),
            ]);
        }
        model.times.lod_seconds = t1.elapsed().as_secs_f64();
        Ok(model)
    }
}

/// One build in progress: the level's constants and the buffers every dispatch binds.
struct BuildRun<'a> {
    builder: &'a SurfaceBuilder,
    ctx: &'a GpuContext,
    level: u32,
    chunk_log2: u32,
    points: wgpu::Buffer,
    dummy_read: wgpu::Buffer,
    dummy_rw: wgpu::Buffer,
}

impl BuildRun<'_> {
    /// The kernels' uniform: `n` items, LOD `k`, and a count.
    fn params(&self, n: u32, k: u32, count: u32) -> wgpu::Buffer {
        uniform(
            &self.ctx.device,
            "rastavox build",
            &[n, self.level, self.chunk_log2, k, count, 0, 0, 0],
        )
    }

    /// The bind group of one dispatch (unused bindings get the small unused buffers).
    fn bind(&self, b: &Binds, p: &wgpu::Buffer) -> KernelBindGroups {
        let (rw, ro) = (&self.dummy_rw, &self.dummy_read);
        let list: [&wgpu::Buffer; 13] = [
            p,
            &self.points,
            b.key.map_or(rw, |k| &k.lo),
            b.key.map_or(rw, |k| &k.hi),
            b.val.unwrap_or(rw),
            b.next.map_or(rw, |k| &k.lo),
            b.next.map_or(rw, |k| &k.hi),
            b.flags.unwrap_or(rw),
            b.counters.unwrap_or(rw),
            b.surface_in.unwrap_or(ro),
            b.attrs_in.unwrap_or(ro),
            b.surface_out.unwrap_or(rw),
            b.attrs_out.unwrap_or(rw),
        ];
        self.builder.kernels.bind_group(&self.ctx.device, &list)
    }

    fn encoder(&self) -> wgpu::CommandEncoder {
        self.ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("rastavox build"),
            })
    }

    /// Extraction of the boundary voxels of the `n` points into `a` (atomic output
    /// slots); returns how many there are.
    fn extract(&self, a: &SortBuffers, n: u32) -> Result<u32, ResourceError> {
        let counter = storage_init(&self.ctx.device, "rastavox counter", &[0]);
        let mut enc = self.encoder();
        let bg = self.bind(
            &Binds {
                key: Some(a),
                val: Some(&a.val),
                counters: Some(&counter),
                ..Default::default()
            },
            &self.params(n, 0, 0),
        );
        self.builder
            .kernels
            .dispatch(&mut enc, "extract", &bg, groups(n));
        self.ctx.submit("surface: extract", [enc.finish()]);
        Ok(read_words(self.ctx, &counter, 0, 1)?[0])
    }

    /// Sorts the `m` keys of `a` by Morton code; true when the result is in `b`.
    fn sort(&self, a: &SortBuffers, b: &SortBuffers, m: u32) -> bool {
        let mut enc = self.encoder();
        let swapped = self
            .builder
            .sort
            .record(&self.ctx.device, &mut enc, a, b, m, 3 * self.level);
        self.ctx.submit("surface: sort", [enc.finish()]);
        swapped
    }

    /// Gathers the finest level from the sorted keys in `a`, finds its chunks and their
    /// chunk-local bounds (six words per chunk, read back).
    fn finest_level(
        &self,
        a: &SortBuffers,
        flags: &wgpu::Buffer,
        m: u32,
    ) -> Result<(GpuSurfaceLevel, Vec<u32>), ResourceError> {
        let d = &self.ctx.device;
        let surface = storage(d, "rastavox surface", u64::from(m));
        let attrs = storage(d, "rastavox attributes", 2 * u64::from(m));
        let mut enc = self.encoder();
        let bg = self.bind(
            &Binds {
                key: Some(a),
                val: Some(&a.val),
                surface_out: Some(&surface),
                attrs_out: Some(&attrs),
                ..Default::default()
            },
            &self.params(m, 0, 0),
        );
        self.builder
            .kernels
            .dispatch(&mut enc, "gather_finest", &bg, groups(m));
        let starts = self.chunk_starts(enc, a, flags, m, 0)?;
        let chunks = starts.len() as u32;
        let starts_buf = storage_init(d, "rastavox chunk starts", &starts);
        let mut init = vec![0u32];
        for _ in 0..chunks {
            init.extend([u32::MAX, u32::MAX, u32::MAX, 0, 0, 0]);
        }
        let bounds_buf = storage_init(d, "rastavox bounds", &init);
        let mut enc = self.encoder();
        let bg = self.bind(
            &Binds {
                val: Some(&starts_buf),
                counters: Some(&bounds_buf),
                surface_in: Some(&surface),
                ..Default::default()
            },
            &self.params(m, 0, chunks),
        );
        self.builder
            .kernels
            .dispatch(&mut enc, "chunk_bounds", &bg, groups(m));
        self.ctx.submit("surface: chunk bounds", [enc.finish()]);
        let local_bounds = read_words(self.ctx, &bounds_buf, 1, 6 * u64::from(chunks))?;
        let level = GpuSurfaceLevel {
            ranges: ranges(&starts, m),
            surface,
            attrs,
            count: m,
        };
        Ok((level, local_bounds))
    }

    /// LOD `k + 1` from `prev` (LOD `k`, keys in `a`): run starts by a scan, one thread per
    /// run merging masks and attributes; its keys go to `b`.
    fn coarser_level(
        &self,
        prev: &GpuSurfaceLevel,
        a: &SortBuffers,
        b: &SortBuffers,
        flags: &wgpu::Buffer,
        k: u32,
    ) -> Result<GpuSurfaceLevel, ResourceError> {
        let d = &self.ctx.device;
        let kernels = &self.builder.kernels;
        let nk = prev.count;
        let mut enc = self.encoder();
        let bg = self.bind(
            &Binds {
                key: Some(a),
                flags: Some(flags),
                ..Default::default()
            },
            &self.params(nk, k, 0),
        );
        kernels.dispatch(&mut enc, "run_flags", &bg, groups(nk));
        let sums = self.builder.sort.scan().record(d, &mut enc, flags, nk);
        let bg = self.bind(
            &Binds {
                key: Some(a),
                val: Some(&a.val),
                flags: Some(flags),
                ..Default::default()
            },
            &self.params(nk, k, 0),
        );
        kernels.dispatch(&mut enc, "run_starts", &bg, groups(nk));
        self.ctx.submit("surface: runs", [enc.finish()]);
        let runs = read_words(self.ctx, &sums, GpuScan::total_index(nk), 1)?[0];
        let surface = storage(d, "rastavox surface", u64::from(runs));
        let attrs = storage(d, "rastavox attributes", 2 * u64::from(runs));
        let mut enc = self.encoder();
        let bg = self.bind(
            &Binds {
                key: Some(a),
                val: Some(&a.val),
                next: Some(b),
                surface_in: Some(&prev.surface),
                attrs_in: Some(&prev.attrs),
                surface_out: Some(&surface),
                attrs_out: Some(&attrs),
                ..Default::default()
            },
            &self.params(nk, k, runs),
        );
        kernels.dispatch(&mut enc, "merge", &bg, groups(runs));
        kernels.dispatch(&mut enc, "merge_keys", &bg, groups(runs));
        let starts = self.chunk_starts(enc, b, flags, runs, k + 1)?;
        Ok(GpuSurfaceLevel {
            ranges: ranges(&starts, runs),
            surface,
            attrs,
            count: runs,
        })
    }

    /// Records `chunk_starts` for the `n` keys of LOD `k` in `keys`, submits `enc` and
    /// reads the sorted first voxel of every chunk back.
    fn chunk_starts(
        &self,
        mut enc: wgpu::CommandEncoder,
        keys: &SortBuffers,
        flags: &wgpu::Buffer,
        n: u32,
        k: u32,
    ) -> Result<Vec<u32>, ResourceError> {
        let counter = storage_init(&self.ctx.device, "rastavox chunk counter", &[0]);
        let bg = self.bind(
            &Binds {
                key: Some(keys),
                flags: Some(flags),
                counters: Some(&counter),
                ..Default::default()
            },
            &self.params(n, k, 0),
        );
        self.builder
            .kernels
            .dispatch(&mut enc, "chunk_starts", &bg, groups(n));
        self.ctx.submit("surface: chunk starts", [enc.finish()]);
        let count = read_words(self.ctx, &counter, 0, 1)?[0];
        let mut starts = read_words(self.ctx, flags, 0, u64::from(count))?;
        starts.sort_unstable();
        Ok(starts)
    }
}

/// Per chunk (first, count) from the sorted chunk starts of `n` voxels.
fn ranges(starts: &[u32], n: u32) -> Vec<[u32; 2]> {
    starts
        .iter()
        .enumerate()
        .map(|(i, &s)| [s, starts.get(i + 1).copied().unwrap_or(n) - s])
        .collect()
}
