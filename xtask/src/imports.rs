//! `cargo xtask imports`: the files of each crate as a graph of who imports whom, and the
//! circles in it (sets of files that import each other).
//!
//! An arrow goes from a file to the file of every module it names: `use` trees, inline
//! `crate::` / `super::` / `self::` paths, and paths that start with one of its child
//! modules. `mod` lines and `pub use` re-exports (a module's facade) are not arrows, and
//! neither are comments, strings or `#[cfg(test)]` modules. No crate does this for Rust
//! sources (`cargo-modules` needs rust-analyzer's whole toolchain), so it is done here on
//! the text; the tests below hold it to hand-built trees.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// The crates whose files may not import each other in a circle (`cargo xtask test` fails
/// otherwise): every crate of the workspace.
pub const NO_CIRCLES: &[&str] = &[
    "crates/bench",
    "crates/engine",
    "crates/frontend",
    "crates/gpu",
    "crates/gpu-build",
    "crates/graph",
    "crates/passes",
    "crates/python",
    "crates/scene-file",
    "crates/voxel",
    "crates/web",
    "tests",
    "xtask",
];

/// The import graph of a set of crates: files relative to the root, arrows between them.
#[derive(Debug, Default)]
pub struct ImportGraph {
    /// Every file, with the files it imports.
    pub arrows: BTreeMap<String, BTreeSet<String>>,
}

/// What the graph of some files looks like.
#[derive(Debug, PartialEq)]
pub struct Summary {
    /// Files.
    pub files: usize,
    /// Arrows between them.
    pub arrows: usize,
    /// Floors: the longest chain of imports, a circle counting as one file.
    pub floors: usize,
    /// Every circle, its files sorted.
    pub circles: Vec<Vec<String>>,
}

impl ImportGraph {
    /// Reads every crate (a folder with `Cargo.toml` and `src/`) below `root`, leaving out
    /// `target`, `.git` and the fuzz workspace.
    pub fn of_workspace(root: &Path) -> Result<Self> {
        let mut graph = Self::default();
        for src in crate_sources(root)? {
            graph.add_crate(root, &src)?;
        }
        Ok(graph)
    }

    /// Adds the files of one crate (`src` is its `src/` folder).
    pub fn add_crate(&mut self, root: &Path, src: &Path) -> Result<()> {
        let mut modules: BTreeMap<Vec<String>, PathBuf> = BTreeMap::new();
        for file in rust_files(src)? {
            let rel = file
                .strip_prefix(src)
                .expect("below src")
                .with_extension("");
            let mut path: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if path.first().is_some_and(|p| p == "bin") {
                continue;
            }
            if matches!(
                path.last().map(String::as_str),
                Some("lib" | "main" | "mod")
            ) {
                path.pop();
            }
            modules.insert(path, file);
        }
        let name = |f: &Path| f.strip_prefix(root).unwrap_or(f).display().to_string();
        for (module, file) in &modules {
            let text = std::fs::read_to_string(file)
                .with_context(|| format!("reading {}", file.display()))?;
            let targets = imported_modules(module, &code_of(&text), &modules);
            self.arrows
                .entry(name(file))
                .or_default()
                .extend(targets.iter().map(|m| name(&modules[m])));
        }
        Ok(())
    }

    /// The summary of the files whose name starts with `prefix` and the arrows among them.
    pub fn summary(&self, prefix: &str) -> Summary {
        let files: Vec<&String> = self
            .arrows
            .keys()
            .filter(|f| f.starts_with(prefix))
            .collect();
        let index: BTreeMap<&String, usize> =
            files.iter().enumerate().map(|(i, f)| (*f, i)).collect();
        let edges: Vec<Vec<usize>> = files
            .iter()
            .map(|f| {
                self.arrows[*f]
                    .iter()
                    .filter_map(|t| index.get(t).copied())
                    .collect()
            })
            .collect();
        let components = strongly_connected(&edges);
        let mut circles: Vec<Vec<String>> = components
            .iter()
            .filter(|c| c.len() > 1)
            .map(|c| {
                let mut names: Vec<String> = c.iter().map(|&i| files[i].clone()).collect();
                names.sort();
                names
            })
            .collect();
        circles.sort();
        Summary {
            files: files.len(),
            arrows: edges.iter().map(Vec::len).sum(),
            floors: floors(&edges, &components),
            circles,
        }
    }
}

/// Every `src/` folder of a crate below `root`.
fn crate_sources(root: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        if dir.join("Cargo.toml").is_file() && dir.join("src").is_dir() {
            out.push(dir.join("src"));
        }
        for e in std::fs::read_dir(&dir).with_context(|| format!("reading {}", dir.display()))? {
            let e = e?;
            let name = e.file_name();
            let skip = matches!(name.to_str(), Some("target" | ".git" | "fuzz" | "src"));
            if e.file_type()?.is_dir() && !skip {
                stack.push(e.path());
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Every `.rs` file below `dir`.
fn rust_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let path = e?.path();
        if path.is_dir() {
            out.extend(rust_files(&path)?);
        } else if path.extension().is_some_and(|x| x == "rs") {
            out.push(path);
        }
    }
    Ok(out)
}

/// The code of a file without comments, string and character literals, `#[cfg(test)]`
/// modules and `pub use` re-exports.
pub fn code_of(text: &str) -> String {
    let code = strip_literals_and_comments(text);
    let code = strip_test_modules(&code);
    strip_reexports(&code)
}

/// Replaces comments with a space and literals with `""`.
fn strip_literals_and_comments(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        let rest = &text[i..];
        if rest.starts_with("//") {
            i += rest.find('\n').unwrap_or(rest.len());
            out.push(' ');
        } else if rest.starts_with("/*") {
            i += rest.find("*/").map_or(rest.len(), |e| e + 2);
            out.push(' ');
        } else if let Some(len) = raw_string_len(rest) {
            i += len;
            out.push_str("\"\"");
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if let Some(len) = char_literal_len(rest) {
            i += len;
            out.push_str("\"\"");
        } else {
            let c = rest.chars().next().expect("not at the end");
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// The length of a raw string literal (`r"…"`, `r#"…"#`, …) at the start of `s`.
fn raw_string_len(s: &str) -> Option<usize> {
    let after_r = s.strip_prefix('r')?;
    let hashes = after_r.len() - after_r.trim_start_matches('#').len();
    let body = after_r[hashes..].strip_prefix('"')?;
    let close = format!("\"{}", "#".repeat(hashes));
    let end = body.find(&close).map_or(body.len(), |e| e + close.len());
    Some(1 + hashes + 1 + end)
}

/// The length of a character literal at the start of `s` (`'a'`, `'\n'`, `'\u{1F600}'`);
/// `None` for a lifetime.
fn char_literal_len(s: &str) -> Option<usize> {
    let body = s.strip_prefix('\'')?;
    if let Some(esc) = body.strip_prefix('\\') {
        return Some(2 + esc.find('\'')? + 1);
    }
    let c = body.chars().next()?;
    body[c.len_utf8()..]
        .starts_with('\'')
        .then(|| 2 + c.len_utf8())
}

/// Removes every `#[cfg(test)] mod name { … }` block (braces matched).
fn strip_test_modules(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let after = &rest[at + "#[cfg(test)]".len()..];
        let trimmed = after.trim_start();
        let is_mod = trimmed.starts_with("mod ") || trimmed.starts_with("pub mod ");
        match (is_mod, after.find('{')) {
            (true, Some(open)) if !after[..open].contains(';') => {
                let mut depth = 0usize;
                let mut end = after.len();
                for (k, ch) in after[open..].char_indices() {
                    match ch {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = open + k + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                rest = &after[end..];
            }
            _ => {
                out.push_str("#[cfg(test)]");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// Removes `pub use …;` and `pub(crate) use …;` statements.
fn strip_reexports(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    loop {
        let found = ["pub use ", "pub(crate) use ", "pub(super) use "]
            .iter()
            .filter_map(|p| rest.find(p))
            .min();
        let Some(at) = found else { break };
        out.push_str(&rest[..at]);
        rest = rest[at..].find(';').map_or("", |e| &rest[at + e + 1..]);
    }
    out.push_str(rest);
    out
}

/// The paths a `use` tree names: `a::{b, c::{d, e as f}}` → `a::b`, `a::c::d`, `a::c::e`.
fn expand_use_tree(tree: &str) -> Vec<String> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        let path = tree.split(" as ").next().unwrap_or(tree).trim();
        return vec![path.to_string()];
    };
    let prefix = tree[..open].trim();
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut out = Vec::new();
    let mut depth = 0;
    let mut start = 0;
    for (k, ch) in inner.char_indices() {
        match ch {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                out.extend(expand_item(prefix, &inner[start..k]));
                start = k + 1;
            }
            _ => {}
        }
    }
    out.extend(expand_item(prefix, &inner[start..]));
    out
}

fn expand_item(prefix: &str, item: &str) -> Vec<String> {
    if item.trim().is_empty() {
        return Vec::new();
    }
    expand_use_tree(item)
        .into_iter()
        .map(|p| format!("{prefix}{p}"))
        .collect()
}

/// Whether `b` may continue an identifier.
fn ident_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

/// Every path the code of module `module` names, as module paths of the crate.
fn imported_modules(
    module: &[String],
    code: &str,
    modules: &BTreeMap<Vec<String>, PathBuf>,
) -> BTreeSet<Vec<String>> {
    let children: BTreeSet<&str> = modules
        .keys()
        .filter(|k| k.len() == module.len() + 1 && k.starts_with(module))
        .map(|k| k[module.len()].as_str())
        .collect();
    let mut paths = Vec::new();
    let bytes = code.as_bytes();
    let mut at = 0;
    while let Some(k) = code[at..].find("use ") {
        let start = at + k;
        at = start + 4;
        if start > 0 && ident_byte(bytes[start - 1]) {
            continue;
        }
        if let Some(end) = code[start..].find(';') {
            paths.extend(expand_use_tree(&code[start + 4..start + end]));
        }
    }
    // Inline paths: an identifier followed by `::`, not itself after `::`.
    let mut i = 0;
    while i < bytes.len() {
        if ident_byte(bytes[i]) && (i == 0 || (!ident_byte(bytes[i - 1]) && bytes[i - 1] != b':')) {
            let mut j = i;
            while j < bytes.len() && (ident_byte(bytes[j]) || code[j..].starts_with("::")) {
                j += if bytes[j] == b':' { 2 } else { 1 };
            }
            let path = &code[i..j];
            let head = path.split("::").next().unwrap_or("");
            if path.contains("::")
                && (["crate", "super", "self"].contains(&head) || children.contains(head))
            {
                paths.push(path.to_string());
            }
            i = j.max(i + 1);
        } else {
            i += 1;
        }
    }
    let mut out = BTreeSet::new();
    for p in paths {
        let parts: Vec<&str> = p
            .split("::")
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        let Some((&head, mut tail)) = parts.split_first() else {
            continue;
        };
        if tail.is_empty() {
            continue;
        }
        let mut base: Vec<String> = match head {
            "crate" => Vec::new(),
            "self" => module.to_vec(),
            "super" => {
                let mut b = module.to_vec();
                b.pop();
                while tail.first() == Some(&"super") {
                    b.pop();
                    tail = &tail[1..];
                }
                b
            }
            h if children.contains(h) => {
                tail = &parts[..];
                module.to_vec()
            }
            _ => continue,
        };
        for seg in tail {
            base.push(seg.to_string());
            if !modules.contains_key(&base) {
                base.pop();
                break;
            }
        }
        if base != module && modules.contains_key(&base) {
            out.insert(base);
        }
    }
    out
}

/// Tarjan's strongly connected components.
fn strongly_connected(edges: &[Vec<usize>]) -> Vec<Vec<usize>> {
    struct State<'a> {
        edges: &'a [Vec<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(s: &mut State<'_>, v: usize) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for &w in &s.edges[v] {
            match s.index[w] {
                None => {
                    visit(s, w);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                _ => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack[w] = false;
                component.push(w);
                if w == v {
                    break;
                }
            }
            s.out.push(component);
        }
    }
    let n = edges.len();
    let mut s = State {
        edges,
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(&mut s, v);
        }
    }
    s.out
}

/// The longest chain of arrows between components, plus one (Tarjan emits a component
/// after every component it reaches, so one pass in that order suffices).
fn floors(edges: &[Vec<usize>], components: &[Vec<usize>]) -> usize {
    let mut of = vec![0; edges.len()];
    for (c, members) in components.iter().enumerate() {
        for &v in members {
            of[v] = c;
        }
    }
    let mut floor = vec![1usize; components.len()];
    for (c, members) in components.iter().enumerate() {
        for &v in members {
            for &w in &edges[v] {
                if of[w] != c {
                    floor[c] = floor[c].max(floor[of[w]] + 1);
                }
            }
        }
    }
    floor.into_iter().max().unwrap_or(0)
}

/// Prints the summary of the whole workspace (or of the checkout after `--root`) and of
/// each crate; false when a crate in [`NO_CIRCLES`] has a circle.
pub fn run(root: &Path, args: &[String]) -> Result<bool> {
    let root = match args {
        [] => root.to_path_buf(),
        [flag, dir] if flag == "--root" => PathBuf::from(dir),
        _ => anyhow::bail!("imports takes only `--root DIR`, got `{}`", args.join(" ")),
    };
    let graph = ImportGraph::of_workspace(&root)?;
    let whole = graph.summary("");
    println!(
        "imports: whole repository: {} files, {} arrows, {} floors, {} circle(s)",
        whole.files,
        whole.arrows,
        whole.floors,
        whole.circles.len()
    );
    let mut ok = true;
    let crates: BTreeSet<String> = graph
        .arrows
        .keys()
        .filter_map(|f| f.split_once("/src/").map(|(c, _)| c.to_string()))
        .collect();
    for c in &crates {
        let s = graph.summary(&format!("{c}/src/"));
        println!(
            "  {c}: {} files, {} arrows, {} floors, {} circle(s)",
            s.files,
            s.arrows,
            s.floors,
            s.circles.len()
        );
        for circle in &s.circles {
            println!("    circle: {}", circle.join(" "));
        }
        if !NO_CIRCLES.contains(&c.as_str()) {
            eprintln!("xtask: crate {c} is not in imports::NO_CIRCLES; add it there");
            ok = false;
        }
        if !s.circles.is_empty() {
            eprintln!("xtask: files of {c} import each other in a circle (see above)");
            ok = false;
        }
    }
    Ok(ok)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, files: &[(&str, &str)]) {
        for (name, text) in files {
            let p = dir.join(name);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, text).unwrap();
        }
    }

    fn graph_of(files: &[(&str, &str)]) -> (tempfile::TempDir, Summary) {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), files);
        let mut g = ImportGraph::default();
        g.add_crate(dir.path(), &dir.path().join("src")).unwrap();
        let s = g.summary("src/");
        (dir, s)
    }

    #[test]
    fn a_two_file_circle_is_found_and_layers_are_counted() {
        let (_d, s) = graph_of(&[
            ("src/lib.rs", "pub mod a;\npub mod b;\npub mod c;\n"),
            ("src/a.rs", "use crate::b::B;\npub struct A;\n"),
            (
                "src/b.rs",
                "pub struct B;\nfn f() { let _ = crate::a::A; }\n",
            ),
            ("src/c.rs", "use crate::{a::A, b};\n"),
        ]);
        assert_eq!(
            s.circles,
            vec![vec!["src/a.rs".to_string(), "src/b.rs".to_string()]]
        );
        assert_eq!(s.files, 4);
        assert_eq!(s.arrows, 4);
        assert_eq!(s.floors, 2);
    }

    #[test]
    fn reexports_comments_strings_and_test_modules_are_not_arrows() {
        let (_d, s) = graph_of(&[
            ("src/lib.rs", "mod a;\nmod b;\npub use a::A;\n"),
            (
                "src/a.rs",
                "use crate::b::B;\n// crate::lib\n/* super::x */\nconst S: &str = \"crate::b\";\n",
            ),
            (
                "src/b.rs",
                "pub struct B;\nconst C: char = '\"';\n#[cfg(test)]\nmod tests {\n    use super::super::a;\n}\n",
            ),
        ]);
        assert!(s.circles.is_empty(), "{:?}", s.circles);
        assert_eq!(s.arrows, 1);
        assert_eq!(s.floors, 2);
    }

    #[test]
    fn super_paths_and_child_modules_resolve_to_their_files() {
        let (_d, s) = graph_of(&[
            ("src/lib.rs", "pub mod kinds;\n"),
            (
                "src/kinds/mod.rs",
                "pub mod one;\npub mod two;\nfn f() { one::run(); }\n",
            ),
            ("src/kinds/one.rs", "pub fn run() { super::two::go() }\n"),
            (
                "src/kinds/two.rs",
                "pub fn go() { let _ = super::helper; }\n",
            ),
        ]);
        // two.rs names `super::helper`, an item of kinds/mod.rs, which calls into one.rs,
        // which calls two.rs: all three in one circle.
        assert_eq!(
            s.circles,
            vec![vec![
                "src/kinds/mod.rs".to_string(),
                "src/kinds/one.rs".to_string(),
                "src/kinds/two.rs".to_string()
            ]]
        );
    }

    #[test]
    fn use_trees_expand_into_every_path() {
        assert_eq!(
            expand_use_tree("crate::a::{b, c::{d, e as f}, self}"),
            [
                "crate::a::b",
                "crate::a::c::d",
                "crate::a::c::e",
                "crate::a::self"
            ]
        );
    }

    #[test]
    fn the_crates_that_must_have_no_circles_have_none() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
        let g = ImportGraph::of_workspace(root).unwrap();
        for c in NO_CIRCLES {
            let s = g.summary(&format!("{c}/src/"));
            assert!(s.files >= 1, "{c}: no files read");
            assert!(s.circles.is_empty(), "{c}: {:?}", s.circles);
        }
    }
}
