//! `ssbvb-gpu-build`: producers of voxel data on the GPU, not render-graph passes. Each
//! turns CPU input into the GPU structures the passes read, and each has a CPU twin in
//! `ssbvb-voxel` that the GPU tests hold it to:
//!
//! - [`voxelize`]: conservative voxelization of a mesh (rasterized, or the exact f64
//!   triangle–box test), sorted into a Morton-ordered voxel set;
//! - [`lod_build`]: the LOD chain, point-cloud words and lookup trees of that set;
//! - [`surface_build`]: RastaVox's surface model (face masks, merged LODs per chunk);
//! - [`level_splice`]: region-local edits spliced into a dynamic object's levels;
//! - [`animated`]: animated meshes, voxelized and built each frame into a dynamic object.

pub mod animated;
pub mod level_splice;
pub mod lod_build;
pub mod surface_build;
pub mod voxelize;
