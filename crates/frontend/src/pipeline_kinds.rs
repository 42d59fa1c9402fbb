//! `ssbvb pipeline kinds [NAME] [--markdown]`: the pass-kind reference, made from the
//! code's own specs (`ssbvb_graph::PassKind`: each kind's doc comment, stage, slots and
//! parameters with their defaults) and the bundled pipelines that use each kind.
//! `docs/pipelines.md` is its `--markdown` output; a test keeps the two equal.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Result, bail};
use ssbvb_graph::{Access, PassKind, PassStage, SlotClass, SlotDesc};

use crate::decl_docs::{self, Decl};

/// The sources of the kinds' parameter types: their fields' doc comments are the
/// parameters' meanings ([`crate::decl_docs`]).
const KIND_SOURCES: &[&str] = &[
    include_str!("../../graph/src/kinds/billboards.rs"),
    include_str!("../../graph/src/kinds/cone_trace.rs"),
    include_str!("../../graph/src/kinds/cube_raster.rs"),
    include_str!("../../graph/src/kinds/dense_dda.rs"),
    include_str!("../../graph/src/kinds/edge_aa.rs"),
    include_str!("../../graph/src/kinds/empty_space_compute.rs"),
    include_str!("../../graph/src/kinds/esvo_ray_cast.rs"),
    include_str!("../../graph/src/kinds/octree_ray_cast.rs"),
    include_str!("../../graph/src/kinds/rastavox.rs"),
    include_str!("../../graph/src/kinds/ray_march_filter.rs"),
    include_str!("../../graph/src/kinds/ray_march_gbuffer.rs"),
    include_str!("../../graph/src/kinds/smooth.rs"),
    include_str!("../../graph/src/kinds/splat_billboards.rs"),
    include_str!("../../graph/src/kinds/temporal.rs"),
    include_str!("../../graph/src/kinds/volume_slices.rs"),
];

/// Each parameter's meaning, in order: the doc comment of its field in the kind's
/// parameter type (`<Kind>Params`, or the type a newtype wraps), followed, for an enum, by
/// its variants' docs. Empty where the declaration is not found (a test fails then).
fn meanings(kind: &PassKind) -> Vec<String> {
    let find = |ty: &str| {
        KIND_SOURCES
            .iter()
            .find_map(|src| decl_docs::parse(src, ty).map(|d| (src, d)))
    };
    let own = format!("{}Params", kind.name());
    let declared = find(&own).or_else(|| {
        // `pub struct SplatBillboardsParams(pub BillboardsParams);`
        let head = format!("pub struct {own}(pub ");
        KIND_SOURCES.iter().find_map(|src| {
            let rest = src.lines().find_map(|l| l.strip_prefix(head.as_str()))?;
            find(rest.trim_end_matches(");"))
        })
    });
    let Some((_, (_, Decl::Struct(fields)))) = declared else {
        return vec![String::new(); kind.parameters().len()];
    };
    kind.parameters()
        .iter()
        .map(|p| {
            let Some(f) = fields.iter().find(|f| f.name == p.name) else {
                return String::new();
            };
            let mut text = f.doc.clone();
            if let Some((_, (_, Decl::Enum(variants)))) = find(&f.ty) {
                for v in variants {
                    text.push_str(&format!(" `{}`: {}", v.name, v.doc));
                }
            }
            text
        })
        .collect()
}

/// The kinds' reference as text: every kind in one line each, or one kind (`name`) whole.
pub fn text(name: Option<&str>) -> Result<String> {
    let users = users(&ssbvb_engine::assets::assets_dir());
    let kinds = PassKind::all_defaults();
    let Some(name) = name else {
        let mut out = String::new();
        for k in &kinds {
            out.push_str(&format!(
                "{:<18} {:<8} {}\n",
                k.name(),
                stage(k),
                first_sentence(k)
            ));
        }
        out.push_str("\n`ssbvb pipeline kinds NAME` shows a kind's slots and parameters.\n");
        return Ok(out);
    };
    let Some(k) = kinds.iter().find(|k| k.name() == name) else {
        bail!(
            "no pass kind `{name}`{}",
            ssbvb_graph::suggest(name, ssbvb_graph::KIND_NAMES.iter().copied())
        );
    };
    let mut out = format!(
        "{} ({} pass)\n  {}\n\n  slots:\n",
        k.name(),
        stage(k),
        paragraph(k)
    );
    for s in k.slots() {
        out.push_str(&format!(
            "    {:<5} {:<24} {:<24} {}\n",
            access(s),
            s.name,
            s.class.describe(),
            accepts(s)
        ));
    }
    out.push_str("\n  parameters:");
    if k.parameters().is_empty() {
        out.push_str(" none\n");
    } else {
        out.push('\n');
        let meanings = meanings(k);
        for ((p, (_, default)), meaning) in k
            .parameters()
            .iter()
            .zip(k.parameter_values())
            .zip(meanings)
        {
            out.push_str(&format!(
                "    {:<16} {:<24} default {:<10} allowed: {}\n      {meaning}\n",
                p.name, p.ty, default, p.range
            ));
        }
    }
    let users = used_by(&users, k.name()).replace('`', "");
    out.push_str(&format!("\n  used by: {users}\n"));
    Ok(out)
}

/// The reference as Markdown (`docs/pipelines.md`).
pub fn markdown() -> String {
    markdown_with(&ssbvb_engine::assets::assets_dir())
}

/// [`markdown`] with the bundled pipelines read from `assets`.
fn markdown_with(assets: &Path) -> String {
    let users = users(assets);
    let mut out = String::from(
        "# Pass kinds\n\n\
         Generated by `ssbvb pipeline kinds --markdown` from the kinds' own specs; a test \
         fails when this file differs from the command's output, so edit the code, not this \
         file. A pipeline file (`assets/pipelines/*.ron`) lists resources and passes; each \
         pass names its kind with its parameters (`kind: RayMarchFilter(max_steps: 512)`; a \
         parameter left out takes its default) and binds each of the kind's slots to a \
         resource (`reads: [...]`, `writes: [...]`, in the slots' order). `ssbvb pipeline \
         check FILE` resolves one and prints its schedule.\n\n",
    );
    for k in PassKind::all_defaults() {
        out.push_str(&format!(
            "## {}\n\n{} pass. {}\n\n",
            k.name(),
            capitalized(stage(&k)),
            paragraph(&k)
        ));
        out.push_str("| slot | access | class | formats or layout |\n|---|---|---|---|\n");
        for s in k.slots() {
            out.push_str(&format!(
                "| `{}` | {} | {} | {} |\n",
                s.name,
                access(s),
                s.class.describe(),
                accepts(s)
            ));
        }
        out.push('\n');
        if k.parameters().is_empty() {
            out.push_str("No parameters.\n\n");
        } else {
            out.push_str(
                "| parameter | type | default | allowed | meaning |\n|---|---|---|---|---|\n",
            );
            let meanings = meanings(&k);
            for ((p, (_, default)), meaning) in k
                .parameters()
                .iter()
                .zip(k.parameter_values())
                .zip(meanings)
            {
                // A `|` inside a table cell must be escaped, even in code.
                let cell = |t: &str| t.replace('|', "\\|");
                out.push_str(&format!(
                    "| `{}` | `{}` | `{}` | {} | {} |\n",
                    p.name,
                    cell(p.ty),
                    cell(&default),
                    cell(p.range),
                    cell(&meaning)
                ));
            }
            out.push('\n');
        }
        out.push_str(&format!("Used by: {}.\n\n", used_by(&users, k.name())));
    }
    out
}

fn stage(k: &PassKind) -> &'static str {
    match k.stage() {
        PassStage::Render => "render",
        PassStage::Compute => "compute",
    }
}

fn capitalized(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map(|f| f.to_uppercase().chain(c).collect())
        .unwrap_or_default()
}

fn access(s: &SlotDesc) -> &'static str {
    match s.access {
        Access::Read => "read",
        Access::Write => "write",
    }
}

/// The formats a texture slot accepts, or a buffer slot's element layout.
fn accepts(s: &SlotDesc) -> String {
    match s.class {
        SlotClass::StorageBuffer(l) | SlotClass::IndirectBuffer(l) => {
            format!("{l:?} ({} bytes each)", l.element_size())
        }
        _ => s
            .class
            .formats()
            .iter()
            .map(|f| format!("{f:?}"))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// The kind's doc comment as one paragraph.
fn paragraph(k: &PassKind) -> String {
    k.description()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The paragraph's first sentence: up to a full stop followed by a capital, not one that
/// ends an abbreviation ("Eq. 1", "cf. Laine").
fn first_sentence(k: &PassKind) -> String {
    let p = paragraph(k);
    let ends = p.match_indices(". ").map(|(i, _)| i).find(|&i| {
        let next_is_capital = p[i + 2..].chars().next().is_some_and(char::is_uppercase);
        let word = p[..i].rsplit(' ').next().unwrap_or_default();
        next_is_capital && !["Eq", "cf", "al", "e.g", "i.e"].contains(&word)
    });
    match ends {
        Some(i) => p[..=i].to_string(),
        None => p,
    }
}

/// Per kind, the pipeline files under `assets/pipelines/` that use it.
fn users(assets: &Path) -> BTreeMap<&'static str, Vec<String>> {
    let mut out: BTreeMap<&'static str, Vec<String>> = BTreeMap::new();
    let dir = assets.join("pipelines");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .map(|rd| rd.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    files.sort();
    for f in files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "ron"))
    {
        let Ok(p) = ssbvb_graph::resolve_file(f) else {
            continue;
        };
        let file = f
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        for pass in &p.passes {
            let list = out.entry(pass.kind.name()).or_default();
            if !list.contains(&file) {
                list.push(file.clone());
            }
        }
    }
    out
}

fn used_by(users: &BTreeMap<&'static str, Vec<String>>, kind: &str) -> String {
    match users.get(kind) {
        Some(files) => files
            .iter()
            .map(|f| format!("`{f}`"))
            .collect::<Vec<_>>()
            .join(", "),
        None => "no bundled pipeline".into(),
    }
}

#[cfg(test)]
mod tests {
    /// `docs/pipelines.md` is the command's output: the reference cannot go stale.
    #[test]
    fn docs_pipelines_md_is_the_generated_reference() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let file = std::fs::read_to_string(root.join("docs/pipelines.md")).unwrap_or_default();
        let generated = super::markdown_with(&root.join("assets"));
        assert!(
            file == generated,
            "docs/pipelines.md differs from `ssbvb pipeline kinds --markdown`; regenerate it \
             with `cargo run -p ssbvb -- pipeline kinds --markdown > docs/pipelines.md`"
        );
    }

    /// Every parameter of every kind has its meaning: the parser found its field.
    #[test]
    fn every_parameter_has_its_meaning() {
        for k in ssbvb_graph::PassKind::all_defaults() {
            for (p, m) in k.parameters().iter().zip(super::meanings(&k)) {
                assert!(m.len() > 10, "{}.{}: `{m}`", k.name(), p.name);
            }
        }
        let filter = ssbvb_graph::PassKind::all_defaults()
            .into_iter()
            .find(|k| k.name() == "RayMarchFilter")
            .unwrap();
        let march = &super::meanings(&filter)[2];
        assert!(
            march.contains("`Exact`: The CPU reference's rules"),
            "{march}"
        );
    }

    /// Every kind `PassKind` has is listed, and one kind shows its slots and parameters.
    #[test]
    fn every_kind_is_listed_and_one_shows_whole() {
        let list = super::text(None).unwrap();
        for k in ssbvb_graph::KIND_NAMES {
            assert!(list.lines().any(|l| l.starts_with(k)), "{k}");
        }
        let one = super::text(Some("RayMarchFilter")).unwrap();
        for want in [
            "RayMarchFilter (compute pass)",
            "read  entry",
            "max_steps",
            "default 1024",
            "at least 1",
            "used by: ",
            "ssbvb_unique.ron",
        ] {
            assert!(one.contains(want), "{want}\n{one}");
        }
        let e = super::text(Some("RayMarchFiltr")).unwrap_err().to_string();
        assert!(e.contains("did you mean `RayMarchFilter`"), "{e}");
    }
}
