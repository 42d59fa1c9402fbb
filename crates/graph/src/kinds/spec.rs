//! What a pass kind is made of: the slots it declares ([`SlotDesc`]), its stage, the
//! [`KindSpec`] trait its parameter type implements, and the `pass_kinds!` macro that turns
//! the list of kinds (in [`crate::kinds`]) into the [`PassKind`](crate::PassKind) enum, the
//! [`OfKind`](crate::OfKind) trait and their dispatch.
//!
//! A kind declares every resource it touches as a [`SlotDesc`] (built with
//! [`SlotDesc::read`] or [`SlotDesc::write`]): name, read or write, and what class of
//! resource (attachment, sampled texture, storage buffer, …) with which formats or
//! layout. Slot names that are shader globals equal the WGSL global names, so
//! `cargo xtask validate-shaders` checks bindings by name through naga reflection. The
//! implementations, with their WGSL file names, are registered in `ssbvb-passes`.

use crate::format::{BufferLayout, Format};

/// Whether a slot is read or written by the pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// The pass reads the resource (it must have a producer).
    Read,
    /// The pass writes the resource.
    Write,
}

/// What class of resource a slot binds, and which formats or layout it accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlotClass {
    /// A render-pass colour attachment.
    ColorAttachment(&'static [Format]),
    /// A depth(-stencil) attachment; when read, it is read-only and its depth aspect is
    /// also a shader global of the slot's name.
    DepthStencilAttachment(&'static [Format]),
    /// A texture read in a shader (`textureLoad` / `textureSample`).
    SampledTexture(&'static [Format]),
    /// A storage texture.
    StorageTexture(&'static [Format]),
    /// A storage buffer of the given element layout.
    StorageBuffer(BufferLayout),
    /// A buffer of indirect arguments of the given layout.
    IndirectBuffer(BufferLayout),
}

impl SlotClass {
    /// Whether the slot is a texture slot (else a buffer slot).
    pub fn is_texture(&self) -> bool {
        !matches!(
            self,
            SlotClass::StorageBuffer(_) | SlotClass::IndirectBuffer(_)
        )
    }

    /// Formats accepted by a texture slot (empty for buffers).
    pub fn formats(&self) -> &'static [Format] {
        match *self {
            SlotClass::ColorAttachment(f)
            | SlotClass::DepthStencilAttachment(f)
            | SlotClass::SampledTexture(f)
            | SlotClass::StorageTexture(f) => f,
            _ => &[],
        }
    }

    /// Layout required by a buffer slot.
    pub fn layout(&self) -> Option<BufferLayout> {
        match *self {
            SlotClass::StorageBuffer(l) | SlotClass::IndirectBuffer(l) => Some(l),
            _ => None,
        }
    }

    /// Whether the slot is an attachment of a render pass (all must share one size).
    pub fn is_attachment(&self) -> bool {
        matches!(
            self,
            SlotClass::ColorAttachment(_) | SlotClass::DepthStencilAttachment(_)
        )
    }

    /// Short human name for error messages.
    pub fn describe(&self) -> &'static str {
        match self {
            SlotClass::ColorAttachment(_) => "colour attachment",
            SlotClass::DepthStencilAttachment(_) => "depth-stencil attachment",
            SlotClass::SampledTexture(_) => "sampled texture",
            SlotClass::StorageTexture(_) => "storage texture",
            SlotClass::StorageBuffer(_) => "storage buffer",
            SlotClass::IndirectBuffer(_) => "indirect buffer",
        }
    }
}

/// One resource slot a pass kind declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlotDesc {
    /// Slot name; for shader-visible slots also the WGSL global's name.
    pub name: &'static str,
    /// Read or write.
    pub access: Access,
    /// Resource class and accepted formats or layout.
    pub class: SlotClass,
}

impl SlotDesc {
    /// A slot the pass reads.
    pub const fn read(name: &'static str, class: SlotClass) -> SlotDesc {
        SlotDesc {
            name,
            access: Access::Read,
            class,
        }
    }

    /// A slot the pass writes.
    pub const fn write(name: &'static str, class: SlotClass) -> SlotDesc {
        SlotDesc {
            name,
            access: Access::Write,
            class,
        }
    }

    /// Whether the slot is a global variable in the pass's WGSL (attachments and indirect
    /// buffers are not, except a read-only depth-stencil, whose depth is sampled).
    pub fn is_shader_global(&self) -> bool {
        match self.class {
            SlotClass::ColorAttachment(_) | SlotClass::IndirectBuffer(_) => false,
            SlotClass::DepthStencilAttachment(_) => self.access == Access::Read,
            _ => true,
        }
    }
}

/// One parameter of a pass kind as the reference shows it (`ssbvb pipeline kinds`): its
/// name in RON, its type, and the values [`KindSpec::problems`] allows. Its default is
/// the kind's own `Default`, read from there ([`crate::PassKind::parameter_values`] of a
/// default kind).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamDesc {
    /// Field name, as written in RON.
    pub name: &'static str,
    /// Type, as written in RON (`u32`, `f32`, `bool`, an enum's variants, `Option<u32>`).
    pub ty: &'static str,
    /// Allowed values, in words.
    pub range: &'static str,
}

impl ParamDesc {
    /// A parameter `name` of type `ty` allowing `range`.
    pub const fn new(name: &'static str, ty: &'static str, range: &'static str) -> Self {
        ParamDesc { name, ty, range }
    }
}

/// Whether a pass runs as a render pass or a compute pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassStage {
    /// Render pass (vertex + fragment entry points).
    Render,
    /// Compute pass.
    Compute,
}

/// What one pass kind declares, implemented by its parameter type (a unit struct for a kind
/// without parameters): how it runs, the slots it binds, the entry points its WGSL defines,
/// and checks of its parameters.
pub trait KindSpec {
    /// The kind's name as written in RON.
    const NAME: &'static str;
    /// Render or compute.
    const STAGE: PassStage;
    /// The slots the kind declares; shader-visible ones bind in this order.
    const SLOTS: &'static [SlotDesc];
    /// Entry points the kind's WGSL must define. By default those of the stage: a render
    /// pass's vertex and fragment stages, a compute pass's one `main`; a kind that
    /// dispatches more than one kernel lists them itself.
    const ENTRY_POINTS: &'static [&'static str] = match Self::STAGE {
        PassStage::Render => &["vs_main", "fs_main"],
        PassStage::Compute => &["main"],
    };

    /// The parameters, in declaration order (none for a kind without).
    const PARAMS: &'static [ParamDesc] = &[];

    /// Problems with the parameters (empty when they are valid).
    fn problems(&self) -> Vec<String> {
        Vec::new()
    }
}

/// Declares the closed set of pass kinds from one list: the `PassKind` enum, the names,
/// one default of each, the `OfKind` trait with its impls, and the dispatch of stage,
/// slots, entry points and parameter checks to each kind's [`KindSpec`]. A kind with
/// parameters is written `Name(ParamsType)` (RON: `Name(field: value)`); one without,
/// `Name = MarkerType` (RON: `Name`). `OfKind` is declared here with the enum it reads,
/// so that this file does not import the list that imports it.
macro_rules! pass_kinds {
    ($( $(#[doc = $doc:literal])* $name:ident $( ( $params:ident ) )? $( = $unit:ident )? ; )*) => {
        /// Every pass kind, with its parameters (RON: `RayMarchFilter(max_steps: 512)`).
        #[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
        pub enum PassKind {
            $( $(#[doc = $doc])* $name $( ($params) )?, )*
        }

        /// The parameters of a pass kind found in a [`PassKind`] value.
        pub trait OfKind: KindSpec + Sized + 'static {
            /// `kind`'s parameters when it is this kind.
            fn of_kind(kind: &PassKind) -> Option<&Self>;
        }

        /// Names of every pass kind, as written in RON (for suggestions).
        pub const KIND_NAMES: &[&str] = &[$( stringify!($name) ),*];

        $( pass_kinds!(@of $name $( ($params) )? $( = $unit )?); )*

        impl PassKind {
            /// The kind's name as written in RON.
            pub fn name(&self) -> &'static str {
                match self {
                    $( PassKind::$name { .. } => stringify!($name), )*
                }
            }

            /// One instance of every kind with default parameters (for registries and
            /// tools).
            pub fn all_defaults() -> Vec<PassKind> {
                vec![$( pass_kinds!(@default $name $( ($params) )? $( = $unit )?) ),*]
            }

            /// What the kind does: its doc comment in the list of kinds.
            pub fn description(&self) -> &'static str {
                match self {
                    $( PassKind::$name { .. } => concat!($( $doc, "\n" ),*), )*
                }
            }

            /// The kind's parameters ([`KindSpec::PARAMS`]).
            pub fn parameters(&self) -> &'static [ParamDesc] {
                match self {
                    $( PassKind::$name { .. } => <$($params)? $($unit)? as KindSpec>::PARAMS, )*
                }
            }

            /// Render or compute.
            pub fn stage(&self) -> PassStage {
                match self {
                    $( PassKind::$name { .. } => <$($params)? $($unit)? as KindSpec>::STAGE, )*
                }
            }

            /// The slots the kind declares.
            pub fn slots(&self) -> &'static [SlotDesc] {
                match self {
                    $( PassKind::$name { .. } => <$($params)? $($unit)? as KindSpec>::SLOTS, )*
                }
            }

            /// Entry points the kind's WGSL must define.
            pub fn entry_points(&self) -> &'static [&'static str] {
                match self {
                    $( PassKind::$name { .. } =>
                        <$($params)? $($unit)? as KindSpec>::ENTRY_POINTS, )*
                }
            }

            /// Problems with the kind's parameters (empty when they are valid).
            pub fn parameter_problems(&self) -> Vec<String> {
                match self {
                    $( PassKind::$name { .. } => <$($params)? $($unit)? as OfKind>::of_kind(self)
                        .map(KindSpec::problems)
                        .unwrap_or_default(), )*
                }
            }
        }
    };
    (@of $name:ident ($params:ident)) => {
        impl OfKind for $params {
            fn of_kind(kind: &PassKind) -> Option<&Self> {
                match kind {
                    PassKind::$name(p) => Some(p),
                    _ => None,
                }
            }
        }
    };
    (@of $name:ident = $unit:ident) => {
        impl OfKind for $unit {
            fn of_kind(kind: &PassKind) -> Option<&Self> {
                match kind {
                    PassKind::$name => Some(&$unit),
                    _ => None,
                }
            }
        }
    };
    (@default $name:ident ($params:ident)) => { PassKind::$name($params::default()) };
    (@default $name:ident = $unit:ident) => { PassKind::$name };
}
pub(crate) use pass_kinds;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attachments_and_indirect_buffers_are_not_shader_globals() {
        let slot = |access, class| match access {
            Access::Read => SlotDesc::read("s", class),
            Access::Write => SlotDesc::write("s", class),
        };
        let f: &'static [Format] = &[];
        for (access, class, global) in [
            (Access::Write, SlotClass::ColorAttachment(f), false),
            (Access::Read, SlotClass::ColorAttachment(f), false),
            (
                Access::Read,
                SlotClass::IndirectBuffer(BufferLayout::DrawIndirect),
                false,
            ),
            // A read-only depth-stencil is sampled; a written one is only an attachment.
            (Access::Read, SlotClass::DepthStencilAttachment(f), true),
            (Access::Write, SlotClass::DepthStencilAttachment(f), false),
            (Access::Read, SlotClass::SampledTexture(f), true),
            (Access::Write, SlotClass::StorageTexture(f), true),
            (
                Access::Write,
                SlotClass::StorageBuffer(BufferLayout::DrawIndirect),
                true,
            ),
        ] {
            assert_eq!(
                slot(access, class).is_shader_global(),
                global,
                "{class:?} {access:?}"
            );
        }
    }
}
