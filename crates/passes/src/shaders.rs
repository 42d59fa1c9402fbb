//! The WGSL sources, embedded at build time, with includes expanded.

use ssbvb_gpu::shader_source::preprocess;

use crate::PassError;

/// Every shader file under `shaders/` by name.
const FILES: &[(&str, &str)] = &[
    (
        "common.inc.wgsl",
        include_str!("../../../shaders/common.inc.wgsl"),
    ),
    (
        "empty_space.wgsl",
        include_str!("../../../shaders/empty_space.wgsl"),
    ),
    (
        "ray_march_filter.wgsl",
        include_str!("../../../shaders/ray_march_filter.wgsl"),
    ),
    (
        "billboards.wgsl",
        include_str!("../../../shaders/billboards.wgsl"),
    ),
    (
        "triangles.wgsl",
        include_str!("../../../shaders/triangles.wgsl"),
    ),
    (
        "dense_dda.wgsl",
        include_str!("../../../shaders/dense_dda.wgsl"),
    ),
    (
        "octree_ray_cast.wgsl",
        include_str!("../../../shaders/octree_ray_cast.wgsl"),
    ),
    (
        "cube_raster.wgsl",
        include_str!("../../../shaders/cube_raster.wgsl"),
    ),
    (
        "ray_cast.inc.wgsl",
        include_str!("../../../shaders/ray_cast.inc.wgsl"),
    ),
    (
        "fullscreen.inc.wgsl",
        include_str!("../../../shaders/fullscreen.inc.wgsl"),
    ),
    ("smooth.wgsl", include_str!("../../../shaders/smooth.wgsl")),
    (
        "sparse_march.inc.wgsl",
        include_str!("../../../shaders/sparse_march.inc.wgsl"),
    ),
    (
        "view_blit.wgsl",
        include_str!("../../../shaders/view_blit.wgsl"),
    ),
    (
        "composite.wgsl",
        include_str!("../../../shaders/composite.wgsl"),
    ),
];

/// The raw text of a shader file.
pub fn raw(name: &str) -> Option<&'static str> {
    FILES.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

/// The WGSL of `name` with includes expanded.
pub fn source(name: &str) -> Result<String, PassError> {
    let main = raw(name).ok_or_else(|| PassError::Shader(format!("{name} is not embedded")))?;
    preprocess(name, main, &|n| raw(n).map(str::to_string))
        .map(|p| p.source)
        .map_err(PassError::Shader)
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_registered_kind_has_its_shader_embedded() {
        for r in crate::REGISTRY {
            super::source(r.shader).unwrap_or_else(|e| panic!("{}: {e}", r.kind));
        }
    }
}
