//! The technique switch: every pipeline file in `assets/pipelines`, listed when the
//! viewer starts (not hard-coded, so pipelines added later show up).

use std::path::{Path, PathBuf};

/// The `.ron` files in `dir`, sorted by name; empty if the folder cannot be read.
pub fn list(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .map(|e| e.path())
                .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "ron"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

/// Short label of a pipeline file: its stem (`ssbvb_direct`, `dense_dda`, …).
pub fn label(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// Whether two paths name the same file (canonically when both exist).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_the_bundled_pipelines() {
        let files = list(&crate::render_cmd::assets_dir().join("pipelines"));
        let names: Vec<String> = files.iter().map(|p| label(p)).collect();
        assert!(names.contains(&"ssbvb_unique".to_string()), "{names:?}");
        assert!(names.contains(&"dense_dda".to_string()), "{names:?}");
        let mut sorted = names.clone();
        sorted.sort();
        assert_eq!(names, sorted);
    }
}
