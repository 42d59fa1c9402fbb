//! `ssbvb-voxel`: everything the renderer consumes, built on the CPU (no wgpu here).
//!
//! Pipeline of the preparation stage (see `docs/architecture.md`, "Preparation"):
//! load a model ([`load`]) → fit it into object space [-1, 1]³ ([`model::ObjectSpace`]) →
//! voxelize it on a 2^L grid ([`voxelize`]) → sparse voxel octree whose every level is a
//! LOD ([`svo`]) → per LOD a packed point cloud ([`asset::PointCloud`]) and a sparse lookup
//! (a 64-ary occupancy tree, [`lookup::SparseLookup`]) → a conservative proxy mesh ([`proxy`]). The exact CPU
//! reference ray caster ([`mod@reference`]) is the ground truth every GPU technique is
//! measured against (over many instances through an [`instance_bvh`]); [`cache`] stores a prepared asset on disk. [`cube_list`] builds the
//! instance data of the cube rasterization baseline.

pub mod accuracy;
pub mod animate;
pub mod asset;
pub mod cache;
pub mod camera;
pub mod cube_list;
pub mod edit;
pub mod edit_journal;
pub mod enclosure;
#[cfg(not(target_arch = "wasm32"))]
pub mod export;
pub mod instance_bvh;
pub mod level_splice;
pub mod lighting;
pub mod load;
pub mod local_edit;
pub mod lookup;
pub mod model;
pub mod prepare;
pub mod procedural;
pub mod progress;
pub mod proxy;
pub mod reference;
pub mod rgba_volume;
pub mod shading;
pub mod surface;
pub mod svo;
pub mod voxelize;
