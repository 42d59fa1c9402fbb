//! The WGSL sources, embedded at build time, with includes expanded.

use ssbvb_gpu::shader_source::preprocess;

use crate::PassError;

/// Every shader file under `shaders/` by name.
const FILES: &[(&str, &str)] = &[(
    "common.inc.wgsl",
    include_str!("../../../shaders/common.inc.wgsl"),
)];

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
