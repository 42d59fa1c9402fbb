//! The pass kinds: one module here and one WGSL file under `shaders/` (same name) per
//! kind, registered by one line of the list below, plus the helpers several kinds share
//! (the G-buffer pipeline, the ray casters' counters, the Rust↔WGSL layout list).

use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::GpuScene;
use ssbvb_graph::{PassKind, ResolvedPipeline, ScheduledPass};

use crate::error::PassError;
use crate::runtime::node::PassNode;
use crate::runtime::registry::{PassInit, Registration, pass_modules};

pub mod gbuffer;
pub mod ray_cast_compute;
pub mod ray_cast_counters;
pub mod wgsl_layout;

// The passes: one line each (module and registration), in registration order.
pass_modules! {
    empty_space::EmptySpace,
    ray_march_filter::RayMarchFilter,
    billboards::Billboards,
    triangles::Triangles,
    smooth::Smooth,
    composite::Composite,
    dense_dda::DenseDda,
    octree_ray_cast::OctreeRayCast,
    esvo_ray_cast::EsvoRayCast,
    cube_raster::CubeRaster,
    splat_billboards::SplatBillboards,
    rastavox::RastaVox,
    cone_trace::ConeTrace,
    cone_composite::ConeComposite,
    volume_slices::VolumeSlices,
    temporal::Temporal,
    edge_aa::EdgeAa,
    empty_space_compute::EmptySpaceCompute,
    smooth_compute::SmoothCompute,
    composite_compute::CompositeCompute,
    ray_march_gbuffer::RayMarchGBuffer,
}

/// The registration of `kind`.
pub fn registration(kind: &PassKind) -> Option<&'static Registration> {
    REGISTRY.iter().find(|r| (r.is_kind)(kind))
}

/// Pass kinds implemented by this crate, with default parameters (their WGSL must exist
/// and match their slots; `cargo xtask validate-shaders` checks it).
pub fn registered_kinds() -> Vec<PassKind> {
    PassKind::all_defaults()
        .into_iter()
        .filter(|k| registration(k).is_some())
        .collect()
}

/// Builds the pass object of a scheduled pass through its [`REGISTRY`] entry.
pub fn create_pass(
    ctx: &GpuContext,
    scene: &GpuScene,
    pipeline: &ResolvedPipeline,
    pass: &ScheduledPass,
) -> Result<Box<dyn PassNode>, PassError> {
    let reg = registration(&pass.kind).ok_or_else(|| PassError::NotImplemented {
        pass: pass.name.clone(),
        kind: pass.kind.name(),
    })?;
    (reg.create)(&PassInit {
        ctx,
        scene,
        pipeline,
        pass,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kind the graph declares but this table lacks fails here (and a pipeline using it
    /// would fail with `PassError::NotImplemented`).
    #[test]
    fn every_declared_kind_is_registered_once() {
        for kind in PassKind::all_defaults() {
            let n = REGISTRY.iter().filter(|r| (r.is_kind)(&kind)).count();
            assert_eq!(n, 1, "pass kind {} is registered {n} times", kind.name());
            // The entry found by the variant carries the kind's name.
            assert_eq!(registration(&kind).map(|r| r.kind), Some(kind.name()));
        }
        assert_eq!(REGISTRY.len(), ssbvb_graph::KIND_NAMES.len());
    }

    #[test]
    fn every_registered_kind_has_its_shader_embedded() {
        for r in REGISTRY {
            ssbvb_gpu::shaders::source(r.shader).unwrap_or_else(|e| panic!("{}: {e}", r.kind));
        }
    }
}
