//! The one table of implemented pass kinds. Each pass type implements [`PassImpl`] next to
//! its code (WGSL file, own bindings, adapter needs, constructor from its typed
//! parameters); the `pass_modules!` list in `kinds/mod.rs` declares each pass module and its
//! [`crate::kinds::REGISTRY`] entry, one line each (the recipe is in `docs/guide.md`,
//! "Add a pass kind").

use ssbvb_gpu::requirements::LimitNeed;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{KindSpec, OfKind, PassKind, ResolvedPipeline, ScheduledPass};

use ssbvb_gpu::scene::GpuScene;

use super::node::PassNode;
use crate::error::PassError;

/// What a pass is built from.
#[derive(Clone, Copy)]
pub struct PassInit<'a> {
    /// The device.
    pub ctx: &'a GpuContext,
    /// The scene (its group-0 layout).
    pub scene: &'a GpuScene,
    /// The whole pipeline (formats of the resources bound to the pass's slots).
    pub pipeline: &'a ResolvedPipeline,
    /// The pass (its kind with parameters, and its bindings).
    pub pass: &'a ScheduledPass,
}

/// What one pass kind needs from an adapter beyond what every pipeline needs.
#[derive(Debug, Clone, Copy)]
pub struct KindNeeds {
    /// Downlevel capabilities (compute shaders come from the kind's stage).
    pub flags: wgpu::DownlevelFlags,
    /// Storage buffers the pass binds itself, in its busiest stage (the scene's come on
    /// top).
    pub storage_buffers: u64,
    /// Bind groups (the scene's is group 0).
    pub bind_groups: u64,
    /// One further limit.
    pub limit: Option<LimitNeed>,
}

impl KindNeeds {
    /// Nothing beyond the scene's needs and group 1.
    pub const NONE: KindNeeds = KindNeeds::new(wgpu::DownlevelFlags::empty(), 0);

    /// `flags` and `storage_buffers`, two bind groups, no further limit.
    pub const fn new(flags: wgpu::DownlevelFlags, storage_buffers: u64) -> Self {
        Self {
            flags,
            storage_buffers,
            bind_groups: 2,
            limit: None,
        }
    }
}

/// The type of a resource a pass owns and binds itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OwnKind {
    /// A sampler (filtering or not).
    Sampler(wgpu::SamplerBindingType),
    /// A read-only storage buffer.
    StorageRead,
    /// A read-write storage buffer.
    StorageReadWrite,
    /// A uniform buffer.
    Uniform,
    /// A 3D texture of `u32` texels read with `textureLoad`.
    Texture3dUint,
    /// A filterable 3D float texture (with mip levels) read with `textureSampleLevel`.
    Texture3dFloat,
    /// A 2D float texture read with `textureLoad`.
    Texture2dFloat,
    /// A 2D texture of unsigned integers, read with `textureLoad`.
    Texture2dUint,
}

/// One resource a pass owns, by its WGSL global name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OwnBinding {
    /// The WGSL global's name.
    pub name: &'static str,
    /// What it is.
    pub kind: OwnKind,
}

/// A pass implementation: everything the table needs to know about it, next to its code.
pub trait PassImpl: PassNode + Sized + 'static {
    /// The kind's parameters in `ssbvb-graph` (a marker type for kinds without any).
    type Params: OfKind;
    /// Its WGSL file under `shaders/` (same name as its module).
    const SHADER: &'static str;
    /// Other forms of that file it may compile instead (chosen by what the device has;
    /// same entry points and bindings: `cargo xtask validate-shaders` checks each).
    const VARIANTS: &'static [&'static str] = &[];
    /// The resources it binds itself, after its slots in group 1 ([`super::bindings`]).
    const OWN: &'static [OwnBinding] = &[];
    /// What it needs from an adapter.
    const NEEDS: KindNeeds = KindNeeds::NONE;
    /// It reads every voxel of a level (its own structures built from whole levels), so
    /// it cannot run on a scene paged under a GPU budget.
    const WHOLE_LEVELS: bool = false;
    /// What it compiles depends on the scene only through its binding counts, whether it
    /// streams, and its group-0 layout, and it keeps nothing of a scene from one frame to
    /// the next: it draws another such scene as a pass made for that scene would (a
    /// renderer of such passes keeps its pipelines when the content changes:
    /// [`crate::Renderer::draws_as_made_for`]).
    const SCENE_FREE: bool = false;

    /// Compiles the pass for `init.pass` with its typed parameters.
    fn new(init: &PassInit<'_>, params: &Self::Params) -> Result<Self, PassError>;
}

/// One implemented pass kind.
pub struct Registration {
    /// The kind's name as written in RON (`PassKind::name`).
    pub kind: &'static str,
    /// Whether a [`PassKind`] value is this kind (its variant, through `OfKind`).
    pub is_kind: fn(&PassKind) -> bool,
    /// Its WGSL file under `shaders/` (same name as its module).
    pub shader: &'static str,
    /// Other forms of that file ([`PassImpl::VARIANTS`]).
    pub variants: &'static [&'static str],
    /// Builds the pass.
    pub create: fn(&PassInit<'_>) -> Result<Box<dyn PassNode>, PassError>,
    /// What it needs from an adapter.
    pub needs: KindNeeds,
    /// The resources it binds itself, after its slots in group 1 ([`super::bindings`]).
    pub own: &'static [OwnBinding],
    /// [`PassImpl::SCENE_FREE`].
    pub scene_free: bool,
}

fn is_kind<P: PassImpl>(kind: &PassKind) -> bool {
    P::Params::of_kind(kind).is_some()
}

fn create<P: PassImpl>(init: &PassInit<'_>) -> Result<Box<dyn PassNode>, PassError> {
    let params = P::Params::of_kind(&init.pass.kind).ok_or_else(|| PassError::NotImplemented {
        pass: init.pass.name.clone(),
        kind: init.pass.kind.name(),
    })?;
    if P::WHOLE_LEVELS && !init.scene.dynamic.is_empty() {
        return Err(PassError::BadScene(format!(
            "pass `{}` (kind {}) builds its structures from the objects' CPU assets and cannot \
             draw objects whose voxels change on the GPU; only the SSBVB pipelines can",
            init.pass.name,
            init.pass.kind.name()
        )));
    }
    if P::WHOLE_LEVELS && init.scene.streaming.is_some() {
        return Err(PassError::NeedsWholeLevels {
            pass: init.pass.name.clone(),
            kind: init.pass.kind.name(),
            pinned: ssbvb_gpu::scene::streaming::PINNED_LEVEL,
        });
    }
    Ok(Box::new(P::new(init, params)?))
}

/// The registration of pass type `P`.
pub const fn register<P: PassImpl>() -> Registration {
    Registration {
        kind: <P::Params as KindSpec>::NAME,
        is_kind: is_kind::<P>,
        shader: P::SHADER,
        variants: P::VARIANTS,
        create: create::<P>,
        needs: P::NEEDS,
        own: P::OWN,
        scene_free: P::SCENE_FREE,
    }
}

/// Declares the pass modules and the registration table from one list (in `kinds/mod.rs`):
/// each entry `module::Type` becomes `pub mod module;` and `register::<module::Type>()` in
/// [`crate::kinds::REGISTRY`], so adding a pass is one line there.
macro_rules! pass_modules {
    ($( $(#[$doc:meta])* $module:ident :: $ty:ident ),* $(,)?) => {
        $( $(#[$doc])* pub mod $module; )*

        /// Every implemented pass kind, in the order of the list in `kinds/mod.rs`.
        pub const REGISTRY: &[$crate::runtime::registry::Registration] =
            &[$( $crate::runtime::registry::register::<$module::$ty>() ),*];
    };
}
pub(crate) use pass_modules;
