//! The RON pipeline file, as written by users (deserialized with serde).
//!
//! See `docs/usage.md`, "Pipeline RON reference", for the format with an example, and
//! `docs/pipelines.md` for every kind. Nothing here is validated beyond syntax:
//! [`crate::resolve`] checks meaning and reports every error.

use std::fmt;

use serde::de::{MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

// The resource types live in `format` (the kinds name them too); re-exported for the file.
pub use crate::format::{BufferLayout, Format};
use crate::kinds::PassKind;

/// A whole pipeline file: named resources, passes and the one output.
#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "Pipeline")]
pub struct PipelineDesc {
    /// Files whose declarations come first (relative to this file; see [`crate::include`]).
    /// Empty in a resolved pipeline's description, which holds what they declared.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub include: Vec<String>,
    /// Transient per-frame resources by name, in file order.
    #[serde(default)]
    pub resources: NamedResources,
    /// Passes in file order (the order only breaks ties in the schedule).
    #[serde(default)]
    pub passes: Vec<PassDesc>,
    /// The resource the frame produces (a texture); everything else serves it. Empty in a
    /// file of shared declarations, which is included, not resolved alone.
    #[serde(default)]
    pub output: String,
    /// Extra resources to keep alive (with the passes that write them) although the output
    /// does not need them: debug views and readback in tests.
    #[serde(default)]
    pub keep: Vec<String>,
}

/// Resources in file order; duplicates are kept so validation can report them.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct NamedResources(pub Vec<(String, ResourceDesc)>);

impl<'de> Deserialize<'de> for NamedResources {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = NamedResources;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map of resource name to Texture(..) or Buffer(..)")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = m.next_entry::<String, ResourceDesc>()? {
                    out.push((k, v));
                }
                Ok(NamedResources(out))
            }
        }
        d.deserialize_map(V)
    }
}

/// One transient resource.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
pub enum ResourceDesc {
    /// A 2D texture.
    Texture {
        /// Texel format.
        format: Format,
        /// Size, relative to the screen or fixed.
        size: SizeDesc,
    },
    /// A buffer of elements of one layout.
    Buffer {
        /// Element layout (each pass slot names the layout it needs).
        layout: BufferLayout,
        /// Element count, relative to the screen's pixel count or fixed.
        count: CountDesc,
    },
}

/// Texture size of a resource.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
pub enum SizeDesc {
    /// The screen (render target) size.
    Screen,
    /// The screen size times a factor (rounded up, at least 1 texel).
    ScreenScaled(f32),
    /// A fixed size in texels.
    Fixed(u32, u32),
}

/// Element count of a buffer resource.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
pub enum CountDesc {
    /// One element per screen pixel.
    ScreenPixels,
    /// Screen pixels times a factor (rounded up, at least 1).
    ScreenPixelsScaled(f32),
    /// A fixed count.
    Fixed(u64),
}

/// One pass of the pipeline.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PassDesc {
    /// Unique pass name (used in errors, timings and `after`).
    pub name: String,
    /// What the pass does, with its typed parameters.
    pub kind: PassKind,
    /// Resources the pass reads, bound to the kind's read slots.
    #[serde(default)]
    pub reads: Bindings,
    /// Resources the pass writes, bound to the kind's write slots.
    #[serde(default)]
    pub writes: Bindings,
    /// Passes this one must run after even without a data dependency (for two passes that
    /// write the same resource: the later one names the earlier here).
    #[serde(default)]
    pub after: Vec<String>,
}

/// Slot → resource bindings of one pass.
///
/// In RON either a list of names, each both the slot and the resource
/// (`["entry", "ssbvb"]`), or a map from slot to resource (`{"normal": "smoothed_normal"}`).
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Bindings(pub Vec<Binding>);

/// One slot bound to one resource.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Binding {
    /// The slot name the pass kind declares (also its WGSL global name).
    pub slot: String,
    /// The resource name from `resources`.
    pub resource: String,
}

impl<'de> Deserialize<'de> for Bindings {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Bindings;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(r#"a list of names ["a", "b"] or a map {"slot": "resource"}"#)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some(name) = s.next_element::<String>()? {
                    out.push(Binding {
                        slot: name.clone(),
                        resource: name,
                    });
                }
                Ok(Bindings(out))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some((slot, resource)) = m.next_entry::<String, String>()? {
                    out.push(Binding { slot, resource });
                }
                Ok(Bindings(out))
            }
        }
        d.deserialize_any(V)
    }
}
