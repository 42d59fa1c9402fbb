//! Animated meshes re-voxelized on the GPU every frame (dynamic objects): the
//! mesh is deformed at time `t` ([`MeshAnimation`], on the CPU: only vertex positions),
//! voxelized on the GPU in the object space of its whole motion ([`GpuVoxelizer`]), its LOD
//! chain and lookups built on the GPU ([`GpuLodBuilder`]) and copied into its object's
//! room in the scene ([`GpuScene::set_object_levels`]); the voxels never leave the GPU on
//! the way (only counts are read back). Each stage is timed, for the cost table beside the
//! static frame. Voxel sets supplied by the application ([`Animator::stream`]) and brush
//! edits (`ssbvb_voxel::edit`) take the same way from the LOD build on.

use web_time::Instant;

use ssbvb_gpu::GpuContext;
use ssbvb_voxel::animate::MeshAnimation;
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::model::{Mesh, ObjectSpace};
use ssbvb_voxel::prepare::prepare_voxel_set;
use ssbvb_voxel::progress::NoProgress;
use ssbvb_voxel::svo::LevelVoxels;
use ssbvb_voxel::voxelize::voxelize_mesh_in;

use crate::lod_build::GpuLodBuilder;
use crate::voxelize::{GpuVoxelizeMethod, GpuVoxelizer};
use ssbvb_gpu::ResourceError;
use ssbvb_gpu::scene::GpuScene;

/// One animated object of a scene.
#[derive(Debug, Clone)]
pub struct AnimatedMesh {
    /// The scene object it drives (uploaded with a [`ssbvb_gpu::scene::DynamicRoom`]).
    pub object: usize,
    /// The mesh at rest.
    pub mesh: Mesh,
    /// How it moves.
    pub animation: MeshAnimation,
    /// The object space of the whole motion.
    pub space: ObjectSpace,
    /// Voxelization level.
    pub level: u32,
}

impl AnimatedMesh {
    /// An animated mesh, its object space from the motion; an error when the mesh has no
    /// usable vertex.
    pub fn new(
        object: usize,
        mesh: Mesh,
        animation: MeshAnimation,
        level: u32,
    ) -> Result<Self, ResourceError> {
        let space = animation.object_space(&mesh).ok_or_else(|| {
            ResourceError::BadScene("the animated mesh has no usable vertex".into())
        })?;
        Ok(Self {
            object,
            mesh,
            animation,
            space,
            level,
        })
    }

    /// The mesh at time `t`.
    pub fn at(&self, t: f64) -> Result<Mesh, ResourceError> {
        self.animation
            .deform(&self.mesh, t)
            .ok_or_else(|| ResourceError::BadScene("the animated mesh has no usable vertex".into()))
    }

    /// The asset at time `t` prepared on the CPU (the first upload, and the reference).
    pub fn cpu_asset(&self, t: f64) -> Result<VoxelAsset, ResourceError> {
        let set = voxelize_mesh_in(&self.at(t)?, self.level, Some(self.space), &NoProgress)
            .map_err(|e| ResourceError::BadScene(e.to_string()))?;
        Ok(prepare_voxel_set(set, &NoProgress).0)
    }
}

/// What one update cost, per stage (host wall clock, each stage waited for; ms).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct UpdateTimes {
    /// Deforming the mesh (CPU).
    pub deform_ms: f64,
    /// GPU voxelization (with its readback of counts).
    pub voxelize_ms: f64,
    /// LOD chain, point clouds and lookups on the GPU.
    pub lod_ms: f64,
    /// Copying the levels into the scene's streams.
    pub copy_ms: f64,
    /// Voxels of the finest level.
    pub voxels: u64,
}

impl UpdateTimes {
    /// Every stage.
    pub fn total_ms(&self) -> f64 {
        self.deform_ms + self.voxelize_ms + self.lod_ms + self.copy_ms
    }
}

/// Runs the per-frame update of animated meshes.
pub struct Animator {
    voxelizer: GpuVoxelizer,
    lods: GpuLodBuilder,
    method: GpuVoxelizeMethod,
}

impl Animator {
    /// Compiles the GPU stages; voxelizes exactly where the adapter has f64 shaders, else
    /// with the conservative-rasterization path.
    pub fn new(ctx: &GpuContext) -> Result<Self, ResourceError> {
        let voxelizer = GpuVoxelizer::new(ctx)?;
        let method = if voxelizer.has_exact() {
            GpuVoxelizeMethod::Exact
        } else {
            GpuVoxelizeMethod::Raster
        };
        Ok(Self {
            voxelizer,
            lods: GpuLodBuilder::new(ctx)?,
            method,
        })
    }

    /// The voxelization it runs.
    pub fn method(&self) -> GpuVoxelizeMethod {
        self.method
    }

    /// Replaces the voxels of dynamic object `object` by `voxels` (the finest level, at the
    /// object's level: Morton-sorted distinct codes with their attributes), supplied by the
    /// application each frame (the paper's streamed objects): the LOD chain, point clouds
    /// and lookups are built on the GPU and copied into the object's room. Only `lod_ms`,
    /// `copy_ms` and `voxels` of the times are set.
    pub fn stream(
        &self,
        ctx: &GpuContext,
        scene: &mut GpuScene,
        object: usize,
        voxels: &LevelVoxels,
    ) -> Result<UpdateTimes, ResourceError> {
        check_voxels(voxels)?;
        let mut times = UpdateTimes {
            voxels: voxels.len() as u64,
            ..Default::default()
        };
        let t0 = Instant::now();
        let levels = self.lods.build(ctx, voxels)?;
        ctx.wait_idle()?;
        times.lod_ms = t0.elapsed().as_secs_f64() * 1e3;
        let t0 = Instant::now();
        scene.set_object_levels(ctx, object, &levels)?;
        ctx.wait_idle()?;
        times.copy_ms = t0.elapsed().as_secs_f64() * 1e3;
        Ok(times)
    }

    /// Brings `mesh`'s object in `scene` to time `t`.
    pub fn update(
        &self,
        ctx: &GpuContext,
        scene: &mut GpuScene,
        mesh: &AnimatedMesh,
        t: f64,
    ) -> Result<UpdateTimes, ResourceError> {
        let mut times = UpdateTimes::default();
        let ms = |t0: Instant| t0.elapsed().as_secs_f64() * 1e3;
        let t0 = Instant::now();
        let deformed = mesh.at(t)?;
        times.deform_ms = ms(t0);
        let t0 = Instant::now();
        // The voxels stay on the GPU from the voxelizer to the scene's streams.
        let (_, voxels, _) = self.voxelizer.voxelize_to_gpu(
            ctx,
            &deformed,
            mesh.level,
            Some(mesh.space),
            None,
            self.method,
        )?;
        ctx.wait_idle()?;
        times.voxelize_ms = ms(t0);
        times.voxels = u64::from(voxels.count);
        let t0 = Instant::now();
        let levels = self.lods.build_gpu(ctx, voxels)?;
        ctx.wait_idle()?;
        times.lod_ms = ms(t0);
        let t0 = Instant::now();
        scene.set_object_levels(ctx, mesh.object, &levels)?;
        ctx.wait_idle()?;
        times.copy_ms = ms(t0);
        Ok(times)
    }
}

/// A streamed voxel set must be what the renderer's ids assume: strictly increasing Morton
/// codes inside the grid, one attribute of each kind per voxel.
fn check_voxels(v: &LevelVoxels) -> Result<(), ResourceError> {
    if v.level > ssbvb_voxel::asset::MAX_LEVEL {
        return Err(ResourceError::BadScene(format!(
            "streamed voxels at level {}, above {}",
            v.level,
            ssbvb_voxel::asset::MAX_LEVEL
        )));
    }
    let n = v.codes.len();
    if v.colors.len() != n || v.normals.len() != n {
        return Err(ResourceError::BadScene(format!(
            "streamed voxels: {n} codes, {} colours, {} normals",
            v.colors.len(),
            v.normals.len()
        )));
    }
    if let Some(i) = (1..n).find(|&i| v.codes[i] <= v.codes[i - 1]) {
        return Err(ResourceError::BadScene(format!(
            "streamed voxels: codes not strictly increasing at {i}"
        )));
    }
    if v.codes.last().is_some_and(|&c| c >= 1u64 << (3 * v.level)) {
        return Err(ResourceError::BadScene(format!(
            "streamed voxels: a cell outside the 2^{} grid",
            v.level
        )));
    }
    Ok(())
}
