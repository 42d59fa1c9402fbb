//! The renderer's per-level structures of a voxel set built on the GPU
//! (`shaders/gpu_lod_build.wgsl`): the LOD chain bottom-up (mipmapping: one
//! parent per run of siblings, attributes averaged as [`LevelVoxels::coarsen`]), each
//! level's point-cloud words (colour, normal) and its sparse lookup (the 64-ary tree of
//! [`ssbvb_voxel::lookup::SparseLookup`], built from the leaves up, a node per run of `key >> 6`, then laid out
//! root first). Every run is found by a flag, a scan ([`GpuScan`]) and a scatter of the
//! starts; the counts that size the next step are read back (a word per step).
//!
//! This is the GPU half of a mesh becoming renderable without CPU preparation: the GPU
//! voxelizer's output goes in sorted, and what comes out equals the CPU preparation
//! (`prepare_voxel_set`) level for level — codes and lookup trees exactly, colours and
//! normals up to one 8-bit step (the CPU sums normals in f64) — which the GPU tests check.
//! Proxies and the scene's streams still come from the CPU path.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_voxel::lookup::{NODE_WORDS, tree_depth};
use ssbvb_voxel::svo::LevelVoxels;

use crate::voxelize::GpuVoxels;
use ssbvb_gpu::ResourceError;
use ssbvb_gpu::kernels::scan::GpuScan;
use ssbvb_gpu::kernels::{
    Bind, KernelBindGroups, Kernels, WORKGROUP, read_words, storage, uniform,
};
use ssbvb_gpu::scene::GpuLevel;

/// The compiled builder.
pub struct GpuLodBuilder {
    kernels: Kernels,
    scan: GpuScan,
}

/// The buffers one dispatch binds (`None`: a binding the kernel does not use, bound to a
/// small unused buffer because a bind group needs every entry).
#[derive(Default)]
struct Binds<'a> {
    keys: Option<(&'a wgpu::Buffer, &'a wgpu::Buffer)>,
    out: Option<(&'a wgpu::Buffer, &'a wgpu::Buffer)>,
    flags: Option<&'a wgpu::Buffer>,
    starts: Option<&'a wgpu::Buffer>,
    nodes: Option<&'a wgpu::Buffer>,
    attrs_in: Option<(&'a wgpu::Buffer, &'a wgpu::Buffer)>,
    attrs_out: Option<(&'a wgpu::Buffer, &'a wgpu::Buffer)>,
    packed: Option<(&'a wgpu::Buffer, &'a wgpu::Buffer)>,
}

impl GpuLodBuilder {
    /// Compiles the kernels.
    pub fn new(ctx: &GpuContext) -> Result<Self, ResourceError> {
        let mut binds = vec![Bind::Uniform];
        binds.extend([Bind::ReadWrite; 13]);
        Ok(Self {
            kernels: Kernels::new(
                ctx,
                "gpu_lod_build.wgsl",
                &binds,
                &[
                    "run_flags",
                    "run_starts",
                    "lookup_group",
                    "add_base",
                    "coarsen",
                    "coarsen_keys",
                    "pack_points",
                ],
            )?,
            scan: GpuScan::new(ctx)?,
        })
    }

    fn bind(&self, d: &wgpu::Device, b: &Binds, params: &wgpu::Buffer) -> KernelBindGroups {
        // Unused bindings get distinct small buffers: one buffer may not be bound twice
        // with writes.
        let ph: Vec<wgpu::Buffer> = (0..13).map(|_| storage(d, "unused", 4)).collect();
        let list: [&wgpu::Buffer; 14] = [
            params,
            b.keys.map_or(&ph[0], |k| k.0),
            b.keys.map_or(&ph[1], |k| k.1),
            b.flags.unwrap_or(&ph[2]),
            b.starts.unwrap_or(&ph[3]),
            b.out.map_or(&ph[4], |k| k.0),
            b.out.map_or(&ph[5], |k| k.1),
            b.nodes.unwrap_or(&ph[6]),
            b.attrs_in.map_or(&ph[7], |a| a.0),
            b.attrs_in.map_or(&ph[8], |a| a.1),
            b.attrs_out.map_or(&ph[9], |a| a.0),
            b.attrs_out.map_or(&ph[10], |a| a.1),
            b.packed.map_or(&ph[11], |p| p.0),
            b.packed.map_or(&ph[12], |p| p.1),
        ];
        self.kernels.bind_group(d, &list)
    }

    /// Runs of `keys[0..n]` by `key >> shift`: records flags, scan and starts, submits, and
    /// returns the run count.
    fn runs(
        &self,
        ctx: &GpuContext,
        keys: (&wgpu::Buffer, &wgpu::Buffer),
        n: u32,
        shift: u32,
        flags: &wgpu::Buffer,
        starts: &wgpu::Buffer,
    ) -> Result<u32, ResourceError> {
        let d = &ctx.device;
        let params = uniform(d, "lod runs", &[n, shift, 0, 0]);
        let b = Binds {
            keys: Some(keys),
            flags: Some(flags),
            starts: Some(starts),
            ..Default::default()
        };
        let bg = self.bind(d, &b, &params);
        let mut enc = d.create_command_encoder(&Default::default());
        self.kernels
            .dispatch(&mut enc, "run_flags", &bg, n.div_ceil(WORKGROUP));
        let sums = self.scan.record(d, &mut enc, flags, n);
        self.kernels
            .dispatch(&mut enc, "run_starts", &bg, n.div_ceil(WORKGROUP));
        ctx.submit("LOD build: runs", [enc.finish()]);
        Ok(read_words(ctx, &sums, GpuScan::total_index(n), 1)?[0])
    }

    /// Builds every level of `finest` (Morton-sorted, distinct codes) down to level 0,
    /// `result[l]` being level `l`.
    pub fn build(
        &self,
        ctx: &GpuContext,
        finest: &LevelVoxels,
    ) -> Result<Vec<GpuLevel>, ResourceError> {
        u32::try_from(finest.len())
            .map_err(|_| ResourceError::TooLarge(format!("{} voxels", finest.len())))?;
        self.build_gpu(ctx, GpuVoxels::upload(&ctx.device, finest))
    }

    /// [`GpuLodBuilder::build`] from voxels already on the GPU (the voxelizer's output).
    pub fn build_gpu(
        &self,
        ctx: &GpuContext,
        finest: GpuVoxels,
    ) -> Result<Vec<GpuLevel>, ResourceError> {
        let d = &ctx.device;
        let n = finest.count;
        let scratch = u64::from(n.max(1));
        let flags = storage(d, "lod flags", scratch);
        let starts = storage(d, "lod starts", scratch);
        let mut level = self.finish_level(
            ctx,
            finest.level,
            n,
            finest.key_lo,
            finest.key_hi,
            finest.colors,
            finest.normals,
            &flags,
            &starts,
        )?;
        let mut out = Vec::new();
        while level.level > 0 {
            let runs = self.runs(
                ctx,
                (&level.key_lo, &level.key_hi),
                level.count,
                3,
                &flags,
                &starts,
            )?;
            let (plo, phi) = (
                storage(d, "codes", runs.into()),
                storage(d, "codes", runs.into()),
            );
            let (pc, pn) = (
                storage(d, "colours", 4 * u64::from(runs)),
                storage(d, "normals", 4 * u64::from(runs)),
            );
            let params = uniform(d, "coarsen", &[level.count, 3, runs, 0]);
            let b = Binds {
                keys: Some((&level.key_lo, &level.key_hi)),
                starts: Some(&starts),
                out: Some((&plo, &phi)),
                attrs_in: Some((&level.colors, &level.normals)),
                attrs_out: Some((&pc, &pn)),
                ..Default::default()
            };
            let mut enc = d.create_command_encoder(&Default::default());
            let bound = self.bind(d, &b, &params);
            let groups = runs.div_ceil(WORKGROUP);
            self.kernels.dispatch(&mut enc, "coarsen", &bound, groups);
            self.kernels
                .dispatch(&mut enc, "coarsen_keys", &bound, groups);
            ctx.submit("LOD build: coarsen", [enc.finish()]);
            let next = self.finish_level(
                ctx,
                level.level - 1,
                runs,
                plo,
                phi,
                pc,
                pn,
                &flags,
                &starts,
            )?;
            out.push(level);
            level = next;
        }
        out.push(level);
        out.reverse();
        Ok(out)
    }

    /// Packs a level's point-cloud words and builds its lookup.
    #[allow(clippy::too_many_arguments)]
    fn finish_level(
        &self,
        ctx: &GpuContext,
        level: u32,
        n: u32,
        key_lo: wgpu::Buffer,
        key_hi: wgpu::Buffer,
        colors: wgpu::Buffer,
        normals: wgpu::Buffer,
        flags: &wgpu::Buffer,
        starts: &wgpu::Buffer,
    ) -> Result<GpuLevel, ResourceError> {
        let d = &ctx.device;
        let packed = storage(d, "point cloud colours", u64::from(n));
        let packed_normals = storage(d, "point cloud normals", u64::from(n.div_ceil(2)));
        let params = uniform(d, "pack", &[n, 0, 0, 0]);
        let b = Binds {
            attrs_in: Some((&colors, &normals)),
            packed: Some((&packed, &packed_normals)),
            ..Default::default()
        };
        let mut enc = d.create_command_encoder(&Default::default());
        self.kernels.dispatch(
            &mut enc,
            "pack_points",
            &self.bind(d, &b, &params),
            n.div_ceil(WORKGROUP),
        );
        ctx.submit("LOD build: pack points", [enc.finish()]);
        // The tree from the leaves up: `depth` groupings, the last one the root.
        let mut per_depth: Vec<(wgpu::Buffer, u32)> = Vec::new();
        let (mut klo, mut khi, mut count) = (key_lo.clone(), key_hi.clone(), n);
        for _ in 0..tree_depth(level) {
            let runs = if count == 0 {
                0
            } else {
                self.runs(ctx, (&klo, &khi), count, 6, flags, starts)?
            };
            let nodes = storage(
                d,
                "lookup nodes",
                NODE_WORDS as u64 * u64::from(runs.max(1)),
            );
            let (olo, ohi) = (
                storage(d, "keys", runs.into()),
                storage(d, "keys", runs.into()),
            );
            if runs > 0 {
                let params = uniform(d, "lookup", &[count, 6, runs, 0]);
                let b = Binds {
                    keys: Some((&klo, &khi)),
                    starts: Some(starts),
                    out: Some((&olo, &ohi)),
                    nodes: Some(&nodes),
                    ..Default::default()
                };
                let mut enc = d.create_command_encoder(&Default::default());
                self.kernels.dispatch(
                    &mut enc,
                    "lookup_group",
                    &self.bind(d, &b, &params),
                    runs.div_ceil(WORKGROUP),
                );
                ctx.submit("LOD build: lookup group", [enc.finish()]);
            }
            per_depth.push((nodes, runs));
            (klo, khi, count) = (olo, ohi, runs);
        }
        // Root first; an empty level still has its (empty) root.
        per_depth.reverse();
        if per_depth[0].1 == 0 {
            per_depth[0].1 = 1;
        }
        let total: u32 = per_depth.iter().map(|p| p.1).sum();
        let nodes = storage(d, "lookup", NODE_WORDS as u64 * u64::from(total));
        let mut enc = d.create_command_encoder(&Default::default());
        let (mut at, mut next_start) = (0u32, 0u32);
        let leaves = per_depth.len() - 1;
        for (k, (buf, count)) in per_depth.iter().enumerate() {
            next_start += count;
            if k < leaves && *count > 0 {
                let params = uniform(d, "add base", &[*count, 0, 0, next_start]);
                let b = Binds {
                    nodes: Some(buf),
                    ..Default::default()
                };
                self.kernels.dispatch(
                    &mut enc,
                    "add_base",
                    &self.bind(d, &b, &params),
                    count.div_ceil(WORKGROUP),
                );
            }
            let bytes = 4 * NODE_WORDS as u64 * u64::from(*count);
            enc.copy_buffer_to_buffer(buf, 0, &nodes, 4 * NODE_WORDS as u64 * u64::from(at), bytes);
            at += count;
        }
        ctx.submit("LOD build: lookup bases", [enc.finish()]);
        Ok(GpuLevel {
            level,
            count: n,
            key_lo,
            key_hi,
            colors,
            normals,
            packed,
            packed_normals,
            nodes,
            node_count: total,
        })
    }
}
