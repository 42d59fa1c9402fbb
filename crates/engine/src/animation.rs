//! Animated scene objects at render time (`animate:` in a scene file, `render --time T`):
//! room in the GPU scene for their changing voxels, the per-frame update on the GPU with
//! its cost per stage (the `animation` section of `render --json`), and the CPU-prepared
//! pose at a time for the reference.

use std::sync::Arc;

use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{DynamicRoom, GpuScene, Scene};
use ssbvb_gpu_build::animated::{AnimatedMesh, Animator, UpdateTimes};
use ssbvb_gpu_build::voxelize::GpuVoxelizeMethod;

use crate::EngineError;

/// Voxel room reserved per level for an animated object, as a multiple of its rest pose.
const GROWTH: f64 = 1.5;

/// `animation` in the report.
#[derive(Debug, Serialize)]
pub struct AnimationReport {
    /// The time drawn, seconds.
    pub time_s: f64,
    /// The GPU voxelization run each update (`null` for the reference, posed on the CPU).
    pub method: Option<GpuVoxelizeMethod>,
    /// Per animated object, the update's cost by stage.
    pub objects: Vec<ObjectUpdate>,
}

/// One object's update.
#[derive(Debug, Serialize)]
pub struct ObjectUpdate {
    /// The scene object.
    pub object: usize,
    /// Per stage (ms) and the voxels of the finest level.
    #[serde(flatten)]
    pub times: UpdateTimes,
    /// All stages (ms).
    pub total_ms: f64,
}

/// Rooms for the animated objects.
pub fn rooms(animated: &[AnimatedMesh]) -> Vec<DynamicRoom> {
    animated
        .iter()
        .map(|a| DynamicRoom {
            object: a.object,
            growth: GROWTH,
        })
        .collect()
}

/// Brings every animated object of `scene` to time `t` on the GPU.
pub fn update_all(
    ctx: &GpuContext,
    scene: &mut GpuScene,
    animator: &Animator,
    animated: &[AnimatedMesh],
    t: f64,
) -> Result<AnimationReport, EngineError> {
    let mut objects = Vec::new();
    for a in animated {
        let times = animator.update(ctx, scene, a, t).map_err(|e| {
            EngineError::from(e).context(format!("animating object {} at t = {t} s", a.object))
        })?;
        objects.push(ObjectUpdate {
            object: a.object,
            total_ms: times.total_ms(),
            times,
        });
    }
    Ok(AnimationReport {
        time_s: t,
        method: Some(animator.method()),
        objects,
    })
}

/// `scene` with each animated object's asset replaced by its pose at `t`, prepared on the
/// CPU (what the reference renders).
pub fn posed(scene: &Scene, animated: &[AnimatedMesh], t: f64) -> Result<Scene, EngineError> {
    let mut out = scene.clone();
    for a in animated {
        let asset = a.cpu_asset(t).map_err(|e| {
            EngineError::from(e).context(format!("posing object {} at t = {t} s", a.object))
        })?;
        out.objects[a.object].asset = Arc::new(asset);
    }
    Ok(out)
}
