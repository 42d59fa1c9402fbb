//! `esvo_ray_cast`: Laine & Karras' ESVO traversal as a baseline (`EsvoRayCast`;
//! `shaders/esvo_ray_cast.wgsl`).
//!
//! The same pass as [`OctreeRayCast`](super::octree_ray_cast::OctreeRayCast) — one
//! fullscreen triangle into the G-buffer, the same octrees uploaded and bound the same way
//! (`OctreeCaster`: `svo_nodes_*`, `svo_level_offsets`, the ray counters), the same
//! outputs and counters — with ESVO's traversal in the fragment shader: coordinates in
//! [1, 2]³, the ray mirrored so its direction is negative on every axis, plane times as
//! `x · tx_coef − tx_bias`, a parent stack indexed by scale, and POP by the highest
//! differing bit of the float positions (no contours). Its counter is loop iterations per
//! ray, reported as `octree_nodes_per_ray` like the stack-based caster's.
//!
//! # Limits
//!
//! Those of the octree caster: levels up to 16 (the octree data's; ESVO's 23-bit scale
//! would allow 23) and octrees within its node bindings. Unlike the reference, ESVO steps
//! diagonally through exact edge or corner ties and accumulates its times, so rays that
//! graze voxel edges may hit a neighbour of the reference's voxel (the GPU tests bound how
//! often).

use ssbvb_gpu::wgpu;
use ssbvb_graph::EsvoRayCastParams;

use super::octree_ray_cast::{NEEDS, OWN, OctreeCaster};
use crate::error::PassError;
use crate::runtime::counters::FrameCounters;
use crate::runtime::node::{CounterSource, PassNode};
use crate::runtime::recorder::Recorder;
use crate::runtime::registry::{KindNeeds, OwnBinding, PassImpl, PassInit};

/// The compiled ESVO pass and the uploaded octrees of the scene.
pub struct EsvoRayCast(OctreeCaster);

impl PassImpl for EsvoRayCast {
    type Params = EsvoRayCastParams;
    const SHADER: &'static str = "esvo_ray_cast.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    const NEEDS: KindNeeds = NEEDS;
    const WHOLE_LEVELS: bool = true;

    /// Compiles the pipeline for the formats bound to `pass`; `max_steps` becomes the WGSL
    /// override `MAX_STEPS`.
    fn new(init: &PassInit<'_>, params: &EsvoRayCastParams) -> Result<Self, PassError> {
        Ok(Self(OctreeCaster::new::<Self>(
            init,
            params.max_steps,
            params.compute,
        )?))
    }
}

impl PassNode for EsvoRayCast {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        self.0.record(encoder, rec)
    }

    fn counters(&self, frame: &CounterSource<'_>, out: &mut FrameCounters) -> Result<(), PassError> {
        self.0.counters(frame, out)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn shader_reads_the_octree_caster_data() {
        // Bindings and the SvoNode layout are checked by `cargo xtask validate-shaders`.
        let src = ssbvb_gpu::shaders::source("esvo_ray_cast.wgsl").unwrap();
        assert!(src.contains("override MAX_STEPS: u32"));
        assert!(src.contains("const SVO_STRIDE: u32 = 18u;"));
        assert!(src.contains("const MAX_LEVEL: u32 = 16u;"));
        assert_eq!(super::super::octree_ray_cast::MAX_OCTREE_LEVEL, 16);
    }
}
