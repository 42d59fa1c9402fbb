//! The repository stands alone: no tracked file may refer to a folder beside the checkout
//! (the project's old `shared` folder one level up). A fresh clone has no such folder, so a
//! path to it is a test or example that cannot pass for a newcomer.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result};

/// The forbidden reference, assembled at run time so this file does not contain it.
fn needle() -> String {
    ["..", "shared"].join("/")
}

/// Tracked files of the repository at `root` (`git ls-files`), or every file under it but
/// `target/` and `.git/` when git is not available (a source tarball).
fn tracked_files(root: &Path) -> Vec<PathBuf> {
    let git = Command::new("git")
        .current_dir(root)
        .args(["ls-files", "-z"])
        .output();
    match git {
        Ok(out) if out.status.success() => out
            .stdout
            .split(|b| *b == 0)
            .filter(|p| !p.is_empty())
            .map(|p| root.join(String::from_utf8_lossy(p).as_ref()))
            .collect(),
        _ => {
            let mut out = Vec::new();
            walk(root, &mut out);
            out
        }
    }
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let p = e.path();
        let name = e.file_name();
        if p.is_dir() {
            if name != "target" && name != ".git" {
                walk(&p, out);
            }
        } else {
            out.push(p);
        }
    }
}

/// `file:line: text` for every line of a tracked text file that refers to the folder
/// beside the repository.
pub fn outside_references(root: &Path) -> Result<Vec<String>> {
    let needle = needle();
    let mut hits = Vec::new();
    for path in tracked_files(root) {
        // Deleted but still tracked (an uncommitted removal): nothing to check.
        let Ok(bytes) = std::fs::read(&path) else {
            continue;
        };
        // Binary files (models, images) are not text that can name a path.
        let Ok(text) = std::str::from_utf8(&bytes) else {
            continue;
        };
        for (i, line) in text.lines().enumerate() {
            if line.contains(&needle) {
                let rel = path.strip_prefix(root).unwrap_or(&path);
                hits.push(format!("{}:{}: {}", rel.display(), i + 1, line.trim()));
            }
        }
    }
    Ok(hits)
}

/// Fails (with every offending line) when a tracked file refers outside the repository.
pub fn check(root: &Path) -> Result<bool> {
    let hits = outside_references(root).context("scanning tracked files")?;
    for h in &hits {
        eprintln!("{h}");
    }
    if !hits.is_empty() {
        eprintln!(
            "xtask: {} line(s) refer to `{}` outside the repository; test models live in \
             assets/models",
            hits.len(),
            needle()
        );
    }
    Ok(hits.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_reference_and_passes_a_clean_tree() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        std::fs::write(root.join("ok.rs"), "let p = \"assets/models/bunny.obj\";\n").unwrap();
        std::fs::write(root.join("bin.dat"), [0xff, 0xfe, 0x00, 0x80]).unwrap();
        assert!(outside_references(root).unwrap().is_empty());
        std::fs::create_dir(root.join("docs")).unwrap();
        std::fs::write(
            root.join("docs/x.md"),
            format!("line one\nsee {}/models/cow.obj\n", needle()),
        )
        .unwrap();
        let hits = outside_references(root).unwrap();
        assert_eq!(hits.len(), 1, "{hits:?}");
        assert!(hits[0].starts_with("docs/x.md:2:"), "{hits:?}");
    }

    #[test]
    fn this_repository_is_clean() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
        let hits = outside_references(root).unwrap();
        assert!(hits.is_empty(), "{hits:#?}");
    }
}
