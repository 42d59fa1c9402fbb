//! WGSL validation with naga, and checks of each registered pass kind's WGSL against the
//! slots it declares (entry points by name and stage, shader-visible slots as globals of the
//! same name: bindings are checked by name, never by position).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use ssbvb_graph::{PassKind, PassStage};
use ssbvb_passes::runtime::registry::OwnBinding;

/// Outcome of validating a folder of shaders.
#[derive(Debug, Default)]
pub struct Report {
    /// Number of `.wgsl` files looked at.
    pub files: usize,
    /// Number of registered pass kinds whose WGSL was checked.
    pub kinds_checked: usize,
    /// One `file:line:col: message` per error.
    pub errors: Vec<String>,
}

fn wgsl_files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    for e in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let p = e?.path();
        if p.is_dir() {
            wgsl_files(&p, out)?;
        } else if p.extension().is_some_and(|x| x == "wgsl") {
            out.push(p);
        }
    }
    Ok(())
}

/// Parses and validates one WGSL source; `Err` holds `file:line:col: message` lines.
pub fn validate_source(file: &str, src: &str) -> Result<naga::Module, Vec<String>> {
    let module = naga::front::wgsl::parse_str(src).map_err(|e| {
        // The first label with a real span (some errors start with an empty one).
        let span = e
            .labels()
            .find(|(s, _)| s.to_range().is_some_and(|r| !r.is_empty()))
            .map(|(s, _)| s);
        let at = span
            .map(|s| s.location(src))
            .or_else(|| e.location(src))
            .map(|l| format!("{}:{}", l.line_number, l.line_position))
            .unwrap_or_else(|| "1:1".into());
        vec![format!("{file}:{at}: {}", e.message())]
    })?;
    let mut v = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    );
    v.validate(&module).map_err(|e| {
        let at = e
            .location(src)
            .map(|l| format!("{}:{}", l.line_number, l.line_position))
            .unwrap_or_else(|| "1:1".into());
        // The full chain of causes ("... in function x: ... expression y ...").
        let mut msg = e.as_inner().to_string();
        let mut src_err: Option<&dyn std::error::Error> = std::error::Error::source(e.as_inner());
        while let Some(s) = src_err {
            msg.push_str(&format!(": {s}"));
            src_err = s.source();
        }
        vec![format!("{file}:{at}: {msg}")]
    })?;
    Ok(module)
}

/// Checks a parsed module against what a pass kind declares.
pub fn check_kind(file: &str, module: &naga::Module, kind: &PassKind) -> Vec<String> {
    let mut errors = Vec::new();
    for (i, ep) in kind.entry_points().iter().enumerate() {
        let want = match (kind.stage(), i) {
            (PassStage::Compute, _) => naga::ShaderStage::Compute,
            (PassStage::Render, 0) => naga::ShaderStage::Vertex,
            (PassStage::Render, _) => naga::ShaderStage::Fragment,
        };
        match module.entry_points.iter().find(|e| e.name == *ep) {
            None => errors.push(format!(
                "{file}: pass kind {} needs entry point `{ep}` ({want:?}), not found",
                kind.name()
            )),
            Some(e) if e.stage != want => errors.push(format!(
                "{file}: entry point `{ep}` of pass kind {} is {:?}, expected {want:?}",
                kind.name(),
                e.stage
            )),
            _ => {}
        }
    }
    for slot in kind.slots().iter().filter(|s| s.is_shader_global()) {
        let found = module
            .global_variables
            .iter()
            .any(|(_, g)| g.name.as_deref() == Some(slot.name));
        if !found {
            errors.push(format!(
                "{file}: pass kind {} declares slot `{}` ({}) but the shader has no global of that name",
                kind.name(),
                slot.name,
                slot.class.describe()
            ));
        }
    }
    errors
}

/// A registered pass kind (default parameters), its WGSL file and its own bindings.
pub type Registered = (PassKind, &'static str, &'static [OwnBinding]);

/// Every registered pass kind, once per WGSL file it may compile (its own and its variants).
pub fn registered() -> Vec<Registered> {
    ssbvb_passes::registered_kinds()
        .into_iter()
        .filter_map(|k| ssbvb_passes::kinds::registration(&k).map(|r| (k, r)))
        .flat_map(|(k, r)| {
            std::iter::once(r.shader)
                .chain(r.variants.iter().copied())
                .map(move |shader| (k.clone(), shader, r.own))
        })
        .collect()
}

/// Validates every `.wgsl` under `dir`, then checks each registered kind's file.
pub fn validate_dir(dir: &Path, kinds: &[Registered]) -> Result<Report> {
    let mut files = Vec::new();
    wgsl_files(dir, &mut files)?;
    files.sort();
    let mut report = Report {
        files: files.len(),
        ..Default::default()
    };
    let mut modules = std::collections::HashMap::new();
    for f in files
        .iter()
        .filter(|f| !f.to_string_lossy().ends_with(".inc.wgsl"))
    {
        let name = f.display().to_string();
        let raw = std::fs::read_to_string(f).with_context(|| format!("reading {name}"))?;
        let base = f.parent().unwrap_or(dir).to_path_buf();
        let read = |inc: &str| {
            if inc == ssbvb_gpu::scene::SCENE_STREAMS_INCLUDE {
                // Generated per scene; check the one-binding-per-stream form.
                return Some(ssbvb_gpu::scene::SceneBindings::SMALLEST.wgsl());
            }
            std::fs::read_to_string(base.join(inc))
                .or_else(|_| std::fs::read_to_string(dir.join(inc)))
                .ok()
        };
        let pre = match ssbvb_gpu::shader_source::preprocess(&name, &raw, &read) {
            Ok(p) => p,
            Err(e) => {
                report.errors.push(e);
                continue;
            }
        };
        // Errors are reported at the file and line the text came from.
        let remap = |errs: Vec<String>| -> Vec<String> {
            errs.into_iter()
                .map(|e| {
                    let rest = e.strip_prefix(&format!("{name}:")).unwrap_or(&e);
                    let (line, tail) = rest.split_once(':').unwrap_or(("1", rest));
                    match line.parse::<usize>() {
                        Ok(l) => {
                            let (file, fl) = pre.locate(l);
                            let file = if file == name {
                                name.clone()
                            } else {
                                base.join(file).display().to_string()
                            };
                            format!("{file}:{fl}:{tail}")
                        }
                        Err(_) => e.clone(),
                    }
                })
                .collect()
        };
        match validate_source(&name, &pre.source).map_err(remap) {
            Ok(m) => {
                modules.insert(
                    f.file_name()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default(),
                    (name, m),
                );
            }
            Err(e) => report.errors.extend(e),
        }
    }
    let layouts = ssbvb_passes::kinds::wgsl_layout::shared_structs();
    let mut mirrored = std::collections::BTreeSet::new();
    let mut names: Vec<_> = modules.keys().cloned().collect();
    names.sort();
    for file in &names {
        let (name, m) = &modules[file];
        let (errors, found) = crate::layout_check::check_structs(name, m, &layouts);
        report.errors.extend(errors);
        mirrored.extend(found);
    }
    // Only when the project's shaders are checked (a test folder holds a few files).
    if kinds.len() >= ssbvb_passes::REGISTRY.len() {
        for l in &layouts {
            if !mirrored.contains(l.wgsl) {
                report.errors.push(format!(
                    "{}: Rust `{}` mirrors WGSL struct `{}`, which no shader declares",
                    dir.display(),
                    l.rust,
                    l.wgsl
                ));
            }
        }
    }
    for (kind, shader, own) in kinds {
        report.kinds_checked += 1;
        match modules.get(*shader) {
            Some((name, m)) => {
                report.errors.extend(check_kind(name, m, kind));
                report
                    .errors
                    .extend(crate::layout_check::check_bindings(name, m, kind, own));
            }
            None if files.iter().any(|f| f.ends_with(shader)) => {} // already reported
            None => report.errors.push(format!(
                "{}: pass kind {} is registered but its shader {shader} is missing",
                dir.display(),
                kind.name(),
            )),
        }
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn broken_wgsl_reports_file_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("ok.wgsl"),
            "@compute @workgroup_size(1) fn main() {}\n",
        )
        .unwrap();
        std::fs::write(
            dir.path().join("bad.wgsl"),
            "// comment\n\nfn f() -> u32 {\n    return 1.5;\n}\n",
        )
        .unwrap();
        std::fs::write(dir.path().join("syntax.wgsl"), "fn f( {\n").unwrap();
        let r = validate_dir(dir.path(), &[]).unwrap();
        assert_eq!(r.errors.len(), 2, "{:#?}", r.errors);
        // An error inside an included file is reported at that file's line.
        std::fs::write(
            dir.path().join("common.inc.wgsl"),
            "const K: u32 = 1u;\nconst L: u32 = 1.5;\n",
        )
        .unwrap();
        std::fs::write(
            dir.path().join("user.wgsl"),
            "//#include \"common.inc.wgsl\"\nfn g() -> u32 { return K; }\n",
        )
        .unwrap();
        let r = validate_dir(dir.path(), &[]).unwrap();
        assert_eq!(r.files, 5);
        assert!(
            r.errors.iter().any(|e| e.contains("common.inc.wgsl:2:")),
            "{:#?}",
            r.errors
        );
        assert_eq!(r.errors.len(), 3, "{:#?}", r.errors);
        assert!(
            r.errors.iter().any(|e| e.contains("bad.wgsl:4:")),
            "{:#?}",
            r.errors
        );
        assert!(
            r.errors.iter().any(|e| e.contains("syntax.wgsl:1:")),
            "{:#?}",
            r.errors
        );
    }

    #[test]
    fn registered_kinds_must_have_matching_entry_points_and_globals() {
        let dir = tempfile::tempdir().unwrap();
        let kind = PassKind::RayMarchFilter(ssbvb_graph::RayMarchFilterParams {
            max_steps: 8,
            ..Default::default()
        });
        // Missing file.
        let kinds = [(kind.clone(), "ray_march_filter.wgsl", &[][..])];
        let r = validate_dir(dir.path(), &kinds).unwrap();
        assert!(
            r.errors[0].contains("ray_march_filter.wgsl is missing"),
            "{:#?}",
            r.errors
        );
        // Wrong: an entry point missing and a slot global misnamed.
        std::fs::write(
            dir.path().join("ray_march_filter.wgsl"),
            "@group(1) @binding(0) var entry_point: texture_2d<f32>;\n\
             @group(1) @binding(1) var<storage, read_write> ssbvb: array<u32>;\n\
             @group(1) @binding(2) var<storage, read_write> billboard_draw: array<u32>;\n\
             @compute @workgroup_size(1) fn main() { _ = textureDimensions(entry_point); ssbvb[0] = 1u; billboard_draw[0] = 1u; }\n",
        )
        .unwrap();
        let r = validate_dir(dir.path(), &kinds).unwrap();
        let text = r.errors.join("\n");
        assert!(text.contains("entry point `clear_draw`"), "{text}");
        assert!(text.contains("slot `entry`"), "{text}");
        // The misnamed global is also undeclared in group 1.
        assert!(text.contains("global `entry_point`"), "{text}");
        assert_eq!(r.errors.len(), 3, "{text}");
    }

    #[test]
    fn the_project_shaders_validate() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let r = validate_dir(&dir, &registered()).unwrap();
        assert!(r.files > 0);
        assert!(r.errors.is_empty(), "{:#?}", r.errors);
    }
}
