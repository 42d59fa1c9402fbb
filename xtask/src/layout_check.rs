//! Checks that need the declarations of `ssbvb-passes`: every pass kind's group-1 bindings
//! sit where its declaration puts them, and every Rust struct that a shader reads has the
//! WGSL struct's size and member offsets (naga computes WGSL's layout rules for us).

use ssbvb_graph::PassKind;
use ssbvb_passes::kinds::wgsl_layout::{StructLayout, is_padding};
use ssbvb_passes::runtime::bindings::{PASS_GROUP, binding_names};

/// Each declared binding of `kind` (slots, then `own`) must be the WGSL global of that
/// name at `@group(1) @binding(position)`, and group 1 may hold nothing else.
pub fn check_bindings(
    file: &str,
    module: &naga::Module,
    kind: &PassKind,
    own: &[ssbvb_passes::runtime::registry::OwnBinding],
) -> Vec<String> {
    let mut errors = Vec::new();
    let names = binding_names(kind.slots(), own);
    for (i, name) in names.iter().enumerate() {
        let Some((_, g)) = module
            .global_variables
            .iter()
            .find(|(_, g)| g.name.as_deref() == Some(*name))
        else {
            // A missing slot global is reported by the slot check; an own binding here.
            if i >= kind.slots().iter().filter(|s| s.is_shader_global()).count() {
                errors.push(format!(
                    "{file}: pass kind {} declares own binding `{name}` but the shader has no \
                     global of that name",
                    kind.name()
                ));
            }
            continue;
        };
        match &g.binding {
            Some(b) if b.group == PASS_GROUP && b.binding == i as u32 => {}
            Some(b) => errors.push(format!(
                "{file}: pass kind {} binds `{name}` at @group({PASS_GROUP}) @binding({i}) (its \
                 position in the declaration), but the shader has @group({}) @binding({})",
                kind.name(),
                b.group,
                b.binding
            )),
            None => errors.push(format!(
                "{file}: pass kind {}: `{name}` is declared as a binding but the shader's global \
                 has no @group/@binding",
                kind.name()
            )),
        }
    }
    for (_, g) in module.global_variables.iter() {
        let (Some(b), Some(name)) = (&g.binding, &g.name) else {
            continue;
        };
        if b.group >= PASS_GROUP && !names.contains(&name.as_str()) {
            errors.push(format!(
                "{file}: global `{name}` at @group({}) @binding({}) is not declared by pass kind \
                 {} (declare it as a slot or an own binding)",
                b.group,
                b.binding,
                kind.name()
            ));
        }
    }
    errors
}

/// Compares every WGSL struct of `module` that has a Rust mirror in `layouts`; returns the
/// errors and the names of the structs found.
pub fn check_structs(
    file: &str,
    module: &naga::Module,
    layouts: &[StructLayout],
) -> (Vec<String>, Vec<&'static str>) {
    let mut errors = Vec::new();
    let mut found = Vec::new();
    for (_, ty) in module.types.iter() {
        let (Some(name), naga::TypeInner::Struct { members, span }) = (&ty.name, &ty.inner) else {
            continue;
        };
        let Some(rust) = layouts.iter().find(|l| l.wgsl == name) else {
            continue;
        };
        found.push(rust.wgsl);
        if *span as usize != rust.size {
            errors.push(format!(
                "{file}: struct `{name}` is {span} bytes in WGSL, but its Rust mirror `{}` is {}",
                rust.rust, rust.size
            ));
        }
        for m in members {
            let Some(mname) = m.name.as_deref() else {
                continue;
            };
            if is_padding(mname) {
                continue;
            }
            match rust.fields.iter().find(|(f, _)| *f == mname) {
                None => errors.push(format!(
                    "{file}: struct `{name}` member `{mname}` (offset {}) has no field in its Rust \
                     mirror `{}`",
                    m.offset, rust.rust
                )),
                Some((_, off)) if *off != m.offset as usize => errors.push(format!(
                    "{file}: struct `{name}` member `{mname}` is at offset {} in WGSL, but at {off} \
                     in its Rust mirror `{}`",
                    m.offset, rust.rust
                )),
                Some(_) => {}
            }
        }
        for (f, off) in &rust.fields {
            if !is_padding(f) && !members.iter().any(|m| m.name.as_deref() == Some(*f)) {
                errors.push(format!(
                    "{file}: Rust `{}` field `{f}` (offset {off}) is missing from WGSL struct \
                     `{name}`",
                    rust.rust
                ));
            }
        }
    }
    (errors, found)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(src: &str) -> naga::Module {
        naga::front::wgsl::parse_str(src).unwrap()
    }

    #[test]
    fn a_moved_binding_and_an_undeclared_one_are_named() {
        let kind = PassKind::Composite;
        let m = parse(
            "@group(1) @binding(0) var albedo: texture_2d<f32>;\n\
             @group(1) @binding(2) var normal: texture_2d<f32>;\n\
             @group(1) @binding(1) var position: texture_2d<f32>;\n\
             @group(1) @binding(3) var extra: texture_2d<f32>;\n",
        );
        let e = check_bindings("c.wgsl", &m, &kind, &[]);
        let text = e.join("\n");
        assert_eq!(e.len(), 3, "{text}");
        assert!(
            text.contains("`normal` at @group(1) @binding(1)") && text.contains("@binding(2)"),
            "{text}"
        );
        assert!(text.contains("global `extra`"), "{text}");
    }

    #[test]
    fn a_struct_that_differs_from_its_mirror_is_named_with_the_field() {
        let layouts = vec![StructLayout {
            wgsl: "DrawArgs",
            rust: "DrawArgs",
            size: 16,
            fields: vec![
                ("vertex_count", 0),
                ("instance_count", 4),
                ("first_vertex", 8),
                ("first_instance", 12),
            ],
        }];
        let ok = parse(
            "struct DrawArgs { vertex_count: u32, instance_count: u32, first_vertex: u32, first_instance: u32 }\n\
             @group(0) @binding(0) var<storage> d: DrawArgs;",
        );
        let (e, found) = check_structs("a.wgsl", &ok, &layouts);
        assert!(e.is_empty(), "{e:?}");
        assert_eq!(found, vec!["DrawArgs"]);
        let bad = parse(
            "struct DrawArgs { vertex_count: u32, first_vertex: u32, instance_count: vec2<u32>, first_instance: u32 }\n\
             @group(0) @binding(0) var<storage> d: DrawArgs;",
        );
        let (e, _) = check_structs("a.wgsl", &bad, &layouts);
        let text = e.join("\n");
        assert!(text.contains("24 bytes in WGSL"), "{text}");
        assert!(
            text.contains("member `first_vertex` is at offset 4 in WGSL, but at 8"),
            "{text}"
        );
        assert!(
            text.contains("member `instance_count` is at offset 8"),
            "{text}"
        );
    }
}
