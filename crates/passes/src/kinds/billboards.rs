//! `billboards`: one camera-facing quad per SSBVB entry, drawn into the G-buffer with
//! stencil = voxel (the paper's step 4; see `shaders/billboards.wgsl` for the quad bound and
//! both shading modes, and [`crate::kinds::triangles`] for the G-buffer layout).
//!
//! wgpu has no geometry shaders, so the quads come from vertex pulling: one
//! `draw_indirect(billboard_draw)` whose arguments the ray-march filter wrote
//! (`{6, hits, 0, 0}`): instance `i` reads SSBVB entry `i`, its six vertices are the corners
//! of two triangles. At most one billboard per covered pixel is drawn.
//!
//! Every quad lies in the view plane of the voxel centre and bounds the cell's projection
//! exactly under perspective ([`Footprint`]: its eight projected corners, or its
//! circumscribed sphere). `size_scale` scales it about its middle; each pixel's own slot
//! must cover that pixel, so a scale below 1 leaves holes. A camera within about a cell of a
//! voxel gets a screen-covering quad whose fragments intersect the voxel's box.
//!
//! - [`BillboardMode::Flat`] (the paper): the quad lies at the voxel centre's depth (up to
//!   ~0.87 cell off the true surface) and is shaded with the voxel's colour and stored
//!   normal; where quads overlap the nearest centre wins, so silhouettes overhang slightly.
//! - [`BillboardMode::RayBox`] (ray–box splatting): every fragment intersects its pixel's
//!   ray with the voxel's box, discards misses and writes the exact hit depth, entered face
//!   and position, so coverage, depth and normals equal the CPU reference's up to f32
//!   rounding; writing `frag_depth` costs early depth testing.
//!
//! Back-face culling (`dot(stored normal, towards the camera) < cull_cos`) is off by
//! default ([`DEFAULT_CULL_COS`]): every SSBVB entry is the first voxel some pixel's ray
//! hit, so culling can only make holes (docs/benchmarks.md has what each threshold loses).

use ssbvb_gpu::wgpu;
use ssbvb_graph::{BillboardMode, BillboardsParams};

use crate::runtime::bindings::PassBindings;
use crate::runtime::counters::FrameCounters;
use crate::runtime::recorder::Recorder;
use crate::kinds::gbuffer::{begin_gbuffer_pass, count_stencil, gbuffer_depth_stencil, gbuffer_targets};
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::{CounterSource, PassNode};
use ssbvb_gpu::shaders;

pub use crate::kinds::gbuffer::STENCIL_VOXEL;

/// Back-face culling threshold used by pipelines: below -1 no billboard is culled (see the
/// module docs for why culling only removes visible voxels).
pub const DEFAULT_CULL_COS: f32 = -2.0;

/// One SSBVB entry (mirror of WGSL `VoxelSlot`), as the ray-march filter writes it. The
/// billboards read its voxel and instance; `t` and `face` are recomputed per fragment in
/// RayBox mode and unused in Flat mode.
pub use crate::kinds::ray_march_filter::VoxelSlot;

/// What the billboard quad bounds on screen (both are exact under perspective).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Footprint {
    /// The bounding rectangle of the cell's eight projected corners: the tightest quad that
    /// covers the voxel (the default).
    #[default]
    Box,
    /// The bounding rectangle of the projection of the cell's circumscribed sphere
    /// (radius `√3/2 ×` the cell's world size for a uniform scale): no corners to project,
    /// but up to `(√3 − 1)/2` of a cell wider on each side.
    Sphere,
}

/// Everything that shapes the billboards pipeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BillboardOptions {
    /// Flat quads or ray–box splats.
    pub mode: BillboardMode,
    /// Scale of the quad about its middle, relative to the exact bound of the footprint (1
    /// covers the voxel's projection; below 1 leaves gaps).
    pub size_scale: f32,
    /// What the quad bounds.
    pub footprint: Footprint,
    /// A billboard whose voxel normal `n` has `dot(n, towards the camera) < cull_cos` is
    /// culled: 0 culls every voxel facing away, -1 or less culls none.
    pub cull_cos: f32,
}

impl BillboardOptions {
    /// The options of a `Billboards` pass kind's parameters (box footprint, culling at
    /// [`DEFAULT_CULL_COS`]).
    pub fn of_params(params: &BillboardsParams) -> Self {
        Self {
            mode: params.mode,
            size_scale: params.size_scale,
            footprint: Footprint::Box,
            cull_cos: DEFAULT_CULL_COS,
        }
    }

    /// The fragment entry point of the mode; `None` for a mode the raster pass has not
    /// (Pixel, the compute splat's: the pipeline check refuses it first).
    fn fragment_entry(&self) -> Option<&'static str> {
        match self.mode {
            BillboardMode::Flat => Some("fs_main"),
            BillboardMode::RayBox => Some("fs_ray_box"),
            BillboardMode::Pixel => None,
        }
    }
}

/// The billboards pass.
pub struct Billboards {
    pipeline: wgpu::RenderPipeline,
    bindings: PassBindings,
    /// Fragment-shader invocations of the last frame (a pipeline-statistics query and its
    /// resolve buffer), where the device has `PIPELINE_STATISTICS_QUERY`.
    fragments: Option<(wgpu::QuerySet, wgpu::Buffer)>,
}

impl Billboards {
    /// Compiles the pipeline with explicit options (for measurements of culling and size).
    pub fn with_options(init: &PassInit<'_>, options: BillboardOptions) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        if !(options.size_scale.is_finite() && options.size_scale > 0.0) {
            return Err(PassError::BadScene(format!(
                "pass `{}`: size_scale must be positive, got {}",
                pass.name, options.size_scale
            )));
        }
        let Some(fs_entry) = options.fragment_entry() else {
            return Err(PassError::BadScene(format!(
                "pass `{}`: rasterized billboards have no mode {:?} (SplatBillboards has)",
                pass.name, options.mode
            )));
        };
        let d = &ctx.device;
        let module = ctx.shader("billboards.wgsl", &shaders::source_for("billboards.wgsl", &scene.bindings)?)?;
        let bindings = PassBindings::new(ctx, pipeline, pass, &[]);
        let layout = pipeline_layout(d, "billboards", scene, Some(&bindings));
        let constants = [
            ("SIZE_SCALE", options.size_scale as f64),
            ("CULL_COS", options.cull_cos as f64),
            (
                "BOX_FOOTPRINT",
                f64::from(u8::from(options.footprint == Footprint::Box)),
            ),
        ];
        let targets = gbuffer_targets(ctx, pipeline, pass);
        // Quads face the camera; culling by the voxel normal happens in the vertex shader.
        // Each billboard is a strip of 4 vertices (billboards.wgsl).
        let pipeline = render_pipeline(
            d,
            &RenderSpec {
                fs_entry,
                topology: wgpu::PrimitiveTopology::TriangleStrip,
                constants: &constants,
                depth_stencil: Some(gbuffer_depth_stencil(ctx, pipeline, pass)),
                ..RenderSpec::new(&pass.name, &module, &layout, &targets)
            },
        );
        let fragments = ctx
            .has(wgpu::Features::PIPELINE_STATISTICS_QUERY)
            .then(|| {
                let set = d.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("billboard fragments"),
                    ty: wgpu::QueryType::PipelineStatistics(
                        wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS,
                    ),
                    count: 1,
                });
                let buf = d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("billboard fragments"),
                    size: 8,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                (set, buf)
            });
        Ok(Self {
            pipeline,
            bindings,
            fragments,
        })
    }
}

impl PassImpl for Billboards {
    type Params = BillboardsParams;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "billboards.wgsl";
    // Drawn with the filter's indirect arguments.
    const NEEDS: KindNeeds = KindNeeds::new(wgpu::DownlevelFlags::INDIRECT_EXECUTION, 1);

    /// Compiles the pipeline of a `Billboards` pass with the kind's parameters.
    fn new(init: &PassInit<'_>, params: &BillboardsParams) -> Result<Self, PassError> {
        Self::with_options(init, BillboardOptions::of_params(params))
    }
}

impl PassNode for Billboards {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let bg = self.bindings.bind_group(rec, &[])?;
        let draw = rec.buffer("billboard_draw");
        let mut pass = begin_gbuffer_pass(encoder, rec, STENCIL_VOXEL);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        pass.set_bind_group(1, &bg, &[]);
        if let Some((set, _)) = &self.fragments {
            pass.begin_pipeline_statistics_query(set, 0);
        }
        pass.draw_indirect(draw, 0);
        if self.fragments.is_some() {
            pass.end_pipeline_statistics_query();
        }
        drop(pass);
        if let Some((set, buf)) = &self.fragments {
            encoder.resolve_query_set(set, 0..1, buf, 0);
        }
        Ok(())
    }

    fn counters(&self, frame: &CounterSource<'_>, out: &mut FrameCounters) -> Result<(), PassError> {
        if let Some((_, buf)) = &self.fragments {
            let bytes = frame.gpu.read_buffer(buf)?;
            let n = u64::from_le_bytes(bytes[..8].try_into().expect("8 bytes"));
            *out.billboard_fragments.get_or_insert(0) += n;
            if let Some(ds) = frame.texture("depth_stencil") {
                out.voxel_pixels = count_stencil(frame.gpu, &ds.texture, STENCIL_VOXEL)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_follow_the_pass_kind() {
        let o = BillboardOptions::of_params(&BillboardsParams {
            mode: BillboardMode::RayBox,
            size_scale: 1.5,
        });
        assert_eq!(o.mode, BillboardMode::RayBox);
        assert_eq!(o.size_scale, 1.5);
        assert_eq!(o.footprint, Footprint::Box);
        assert!(o.cull_cos < -1.0, "culling is off by default");
        assert_eq!(o.fragment_entry(), Some("fs_ray_box"));
    }

    #[test]
    fn shader_has_both_fragment_entries_and_the_overrides() {
        let src = shaders::source("billboards.wgsl").unwrap();
        for name in [
            "fn vs_main",
            "fn fs_main",
            "fn fs_ray_box",
            "override SIZE_SCALE",
            "override CULL_COS",
            "override BOX_FOOTPRINT",
            "var<storage, read> ssbvb",
        ] {
            assert!(src.contains(name), "{name}");
        }
        assert_eq!(std::mem::size_of::<VoxelSlot>(), 32);
    }
}
