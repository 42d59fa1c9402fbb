//! The GPU test binary: every test shares one device (see `ssbvb_tests::ctx`). Modules are
//! grouped by pass or by property.

mod all_models;
mod billboard_footprint;
mod billboard_harness;
mod billboards;
mod chunks;
mod cone_trace;
mod core_frames;
mod cube_raster;
mod dense_dda;
mod device_loss;
mod dynamic;
mod edge_aa;
mod embed;
mod empty_space;
mod esvo_ray_cast;
mod gpu_sort;
mod gpu_voxelize;
mod local_edit;
mod octree_ray_cast;
mod peel;
mod pipeline;
mod pixel_splat;
mod rastavox;
mod ray_cast_compute;
mod ray_casters;
mod ray_march_filter;
mod scale;
mod smooth_composite;
mod splat;
mod streaming;
mod temporal;
mod ties;
mod triangles;
mod volumes;
mod webgpu_limits;
