//! `cone_composite`: deferred Blinn-Phong with the cone tracer's ambient occlusion, soft
//! shadow and bounce (`ConeComposite`; `shaders/cone_composite.wgsl`; the CPU twin is
//! `ssbvb_voxel::shading::shade_lit`). The pipeline and recording are the composite's.

use ssbvb_gpu::wgpu;
use ssbvb_graph::ConeCompositeKind;

use crate::kinds::composite::Composite;
use crate::runtime::recorder::Recorder;
use crate::runtime::registry::{PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::PassNode;

/// The cone-lit composite pass.
pub struct ConeComposite(Composite);

impl PassImpl for ConeComposite {
    type Params = ConeCompositeKind;
    const SHADER: &'static str = "cone_composite.wgsl";

    fn new(init: &PassInit<'_>, _params: &ConeCompositeKind) -> Result<Self, PassError> {
        Composite::compile(init, Self::SHADER).map(Self)
    }
}

impl PassNode for ConeComposite {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        self.0.record(encoder, rec)
    }
}
