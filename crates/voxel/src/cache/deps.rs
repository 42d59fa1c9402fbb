//! The files a cached asset depends on besides its model file (MTL libraries, textures,
//! glTF buffers and images), so that editing any of them rebuilds the asset.
//!
//! Beside the cache files, `<model hash>.deps` lists, for a model file's content, every
//! file its last load read or looked for, with the content hash each had (or `missing`).
//! The cache file of the asset is keyed by the model hash combined with those hashes: a
//! changed, added or removed dependency gives another key, and the rebuild reason names the
//! file. The list is text, one `<32 hex digits or "missing"> <path>` per line, written to a
//! temporary file and renamed.

use std::io::Write;
use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::Xxh3;

use super::hash_source;

/// One dependency and the content hash it had (`None`: it did not exist).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Dependency {
    /// The file.
    pub path: PathBuf,
    /// XXH3-128 of its content, `None` when it could not be read.
    pub hash: Option<u128>,
}

impl Dependency {
    /// `path` (made absolute, so the list means the same from any working directory)
    /// with its current content hash.
    pub fn now(path: &Path) -> Self {
        Self {
            path: absolute(path),
            hash: hash_source(path).ok(),
        }
    }
}

/// `path` canonicalized; for a file that does not exist, its canonical folder joined with
/// its name; else `path` as given.
fn absolute(path: &Path) -> PathBuf {
    if let Ok(p) = std::fs::canonicalize(path) {
        return p;
    }
    match (path.parent(), path.file_name()) {
        (Some(dir), Some(name)) => std::fs::canonicalize(if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        })
        .map(|d| d.join(name))
        .unwrap_or_else(|_| path.to_path_buf()),
        _ => path.to_path_buf(),
    }
}

/// The dependency list of a model whose content hashes to `model_hash`.
pub(crate) fn list_path(dir: &Path, model_hash: u128) -> PathBuf {
    dir.join(format!("{model_hash:032x}.deps"))
}

/// The cache key of a model and its dependencies.
pub(crate) fn combined_key(model_hash: u128, deps: &[Dependency]) -> u128 {
    let mut h = Xxh3::new();
    h.update(&model_hash.to_le_bytes());
    for d in deps {
        h.update(d.path.to_string_lossy().as_bytes());
        h.update(&[0]);
        match d.hash {
            Some(x) => {
                h.update(&[1]);
                h.update(&x.to_le_bytes());
            }
            None => h.update(&[2]),
        }
    }
    h.digest128()
}

/// Reads a dependency list; `None` when it is missing or malformed (then the asset is
/// rebuilt and the list written again).
pub(crate) fn read_list(path: &Path) -> Option<Vec<Dependency>> {
    let text = std::fs::read_to_string(path).ok()?;
    text.lines()
        .map(|line| {
            let (hash, file) = line.split_once(' ')?;
            let hash = match hash {
                "missing" => None,
                h if h.len() == 32 => Some(u128::from_str_radix(h, 16).ok()?),
                _ => return None,
            };
            (!file.is_empty()).then(|| Dependency {
                path: PathBuf::from(file),
                hash,
            })
        })
        .collect()
}

/// Writes a dependency list atomically. Paths with a line break cannot be listed.
pub(crate) fn write_list(path: &Path, deps: &[Dependency]) -> std::io::Result<()> {
    let mut text = String::new();
    for d in deps {
        let p = d.path.to_string_lossy();
        if p.contains('\n') || p.contains('\r') {
            return Err(std::io::Error::other(format!(
                "{p:?}: a dependency path with a line break cannot be recorded"
            )));
        }
        match d.hash {
            Some(h) => text.push_str(&format!("{h:032x} {p}\n")),
            None => text.push_str(&format!("missing {p}\n")),
        }
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let mut tmp = tempfile::NamedTempFile::new_in(dir)?;
    tmp.write_all(text.as_bytes())?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// The dependencies among `recorded` whose content differs now, and the list as it is now.
pub(crate) fn changes(recorded: &[Dependency]) -> (Vec<PathBuf>, Vec<Dependency>) {
    let now: Vec<Dependency> = recorded.iter().map(|d| Dependency::now(&d.path)).collect();
    let changed = recorded
        .iter()
        .zip(&now)
        .filter(|(a, b)| a.hash != b.hash)
        .map(|(a, _)| a.path.clone())
        .collect();
    (changed, now)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_round_trip_and_keys_follow_every_hash() {
        let dir = tempfile::tempdir().unwrap();
        let deps = vec![
            Dependency {
                path: PathBuf::from("/a/b c.mtl"),
                hash: Some(0x1234_5678_9abc_def0_1122_3344_5566_7788),
            },
            Dependency {
                path: PathBuf::from("/a/missing.png"),
                hash: None,
            },
        ];
        let p = list_path(dir.path(), 7);
        write_list(&p, &deps).unwrap();
        assert_eq!(read_list(&p).unwrap(), deps);
        let k = combined_key(7, &deps);
        assert_ne!(k, combined_key(8, &deps));
        let mut other = deps.clone();
        other[1].hash = Some(1);
        assert_ne!(k, combined_key(7, &other));
        assert_ne!(k, combined_key(7, &deps[..1]));
        // Malformed lists are not trusted.
        std::fs::write(&p, "zz /x\n").unwrap();
        assert!(read_list(&p).is_none());
        std::fs::write(&p, "missing\n").unwrap();
        assert!(read_list(&p).is_none());
        // A hash must have its 32 digits (a short one would parse as a number).
        std::fs::write(&p, "abc /x.mtl\n").unwrap();
        assert!(read_list(&p).is_none());
        // Either line break makes a path unlistable.
        for bad in ["/a\nb.mtl", "/a\rb.mtl"] {
            let d = [Dependency {
                path: PathBuf::from(bad),
                hash: None,
            }];
            assert!(write_list(&p, &d).is_err(), "{bad:?}");
        }
    }

    /// Found by cargo-mutants: dependencies that do not exist are keyed by an absolute path
    /// (their canonical folder and name), so the key does not depend on the working folder.
    #[test]
    fn missing_files_are_named_by_their_canonical_folder() {
        let dir = tempfile::tempdir().unwrap();
        let canonical = std::fs::canonicalize(dir.path()).unwrap();
        let missing = dir.path().join("sub/../nothing.mtl");
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        assert_eq!(absolute(&missing), canonical.join("nothing.mtl"));
        let here = std::fs::canonicalize(".").unwrap();
        assert_eq!(
            absolute(Path::new("no-such-file.mtl")),
            here.join("no-such-file.mtl")
        );
        let existing = dir.path().join("sub");
        assert_eq!(absolute(&existing), canonical.join("sub"));
    }
}
