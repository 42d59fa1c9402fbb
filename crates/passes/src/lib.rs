//! `ssbvb-passes`: the implementations of the graph's pass kinds, one module and one WGSL
//! file (under `shaders/`, same name) per kind.
//!
//! [`registered_kinds`] lists the kinds that have an implementation here; tools such as
//! `cargo xtask validate-shaders` check each one's WGSL (entry points, and every
//! shader-visible slot as a global of the same name).

use ssbvb_graph::PassKind;

/// Pass kinds implemented by this crate (their WGSL must exist and match their slots).
///
/// The SSBVB passes land with the SSBVB frame; until then no kind is executable and
/// `ssbvb render` says so.
pub fn registered_kinds() -> Vec<PassKind> {
    Vec::new()
}
