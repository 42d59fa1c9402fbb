//! The engine's errors: one enum, each variant naming what went wrong and, where it can,
//! the file or field. Nothing the engine is handed (a file, an array, a size) panics it.

use ssbvb_gpu::{GpuError, ResourceError};
use ssbvb_passes::PassError;
use ssbvb_voxel::cache::PrepareError;

/// Why an engine call failed.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// The device or a GPU call failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// A GPU resource (the scene, a pool) could not be built.
    #[error(transparent)]
    Resource(#[from] ResourceError),
    /// A pass could not be built or run.
    #[error(transparent)]
    Pass(#[from] PassError),
    /// A model could not be loaded or prepared.
    #[error(transparent)]
    Prepare(#[from] PrepareError),
    /// A scene file is malformed (the message names the file, line and field).
    #[error(transparent)]
    SceneFile(#[from] ssbvb_scene_file::SceneError),
    /// A pipeline file does not resolve (every error of the file, with its lines).
    #[error("{0}")]
    Pipeline(String),
    /// A file could not be read or written.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: String,
        /// What the system said.
        error: std::io::Error,
    },
    /// An argument is unusable: the message names it and what was expected.
    #[error("{0}")]
    Invalid(String),
    /// Voxels given as arrays are unusable (shape, type, origin, size).
    #[error("voxel arrays: {0}")]
    Arrays(#[from] crate::arrays::ArrayError),
    /// The GPU could not hold what was asked (the message says what to lower).
    #[error("{0}")]
    OutOfMemory(String),
    /// An error with where it happened (a scene object, a pass, a frame).
    #[error("{context}: {error}")]
    Context {
        /// Where: `scene x.ron: object bunny.obj`, `animating object 2`.
        context: String,
        /// The error.
        error: Box<EngineError>,
    },
}

impl EngineError {
    /// The refused allocation (resource, bytes) when this is an out-of-memory error from
    /// the driver, through any wrapper.
    pub fn refused_allocation(&self) -> Option<(String, u64)> {
        match self {
            EngineError::Gpu(g) => refused_by_gpu(g),
            EngineError::Resource(r) => refused_by_resource(r),
            EngineError::Pass(p) => refused_by_pass(p),
            EngineError::Context { error, .. } => error.refused_allocation(),
            _ => None,
        }
    }

    /// This error with `context` before it.
    pub fn context(self, context: impl Into<String>) -> Self {
        EngineError::Context {
            context: context.into(),
            error: Box::new(self),
        }
    }

    /// An I/O error on `path`.
    pub fn io(path: &std::path::Path, error: std::io::Error) -> Self {
        EngineError::Io {
            path: path.display().to_string(),
            error,
        }
    }
}

/// The refused allocation (resource, bytes) of a driver's out-of-memory error.
pub(crate) fn refused_by_gpu(g: &GpuError) -> Option<(String, u64)> {
    match g {
        GpuError::OutOfMemory { resource, bytes } => Some((resource.clone(), *bytes)),
        _ => None,
    }
}

/// [`refused_by_gpu`] of a resource error.
pub(crate) fn refused_by_resource(r: &ResourceError) -> Option<(String, u64)> {
    match r {
        ResourceError::Gpu(g) => refused_by_gpu(g),
        _ => None,
    }
}

/// [`refused_by_gpu`] of a pass error.
pub(crate) fn refused_by_pass(p: &PassError) -> Option<(String, u64)> {
    match p {
        PassError::Gpu(g) => refused_by_gpu(g),
        PassError::Resource(r) => refused_by_resource(r),
        _ => None,
    }
}

/// `.context(..)` on results whose error converts into [`EngineError`].
pub trait ResultExt<T> {
    /// The error, if any, with `context` before it.
    fn context_with(self, context: impl FnOnce() -> String) -> Result<T, EngineError>;
}

impl<T, E: Into<EngineError>> ResultExt<T> for Result<T, E> {
    fn context_with(self, context: impl FnOnce() -> String) -> Result<T, EngineError> {
        self.map_err(|e| e.into().context(context()))
    }
}

impl From<ssbvb_voxel::load::LoadError> for EngineError {
    fn from(e: ssbvb_voxel::load::LoadError) -> Self {
        EngineError::Prepare(PrepareError::Load(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refused_allocation_is_found_through_every_wrapper() {
        let refused = || GpuError::OutOfMemory {
            resource: "voxel colours 0".into(),
            bytes: 3 << 20,
        };
        let want = Some(("voxel colours 0".to_string(), 3 << 20));
        assert_eq!(EngineError::Gpu(refused()).refused_allocation(), want);
        let scene = EngineError::Resource(ResourceError::Gpu(refused())).context("opening");
        assert_eq!(scene.refused_allocation(), want);
        let pass = EngineError::Pass(PassError::Resource(ResourceError::Gpu(refused())));
        assert_eq!(pass.refused_allocation(), want);
        assert_eq!(
            EngineError::Pass(PassError::Gpu(refused())).refused_allocation(),
            want
        );
        let other = EngineError::Resource(ResourceError::TooLarge("x".into()));
        assert_eq!(other.refused_allocation(), None);
        assert_eq!(
            scene.to_string(),
            format!("opening: {}", refused()),
            "a context is said once, before the error"
        );
    }
}
