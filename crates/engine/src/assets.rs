//! The bundled assets (default scene, pipelines, the bunny) found wherever a program built
//! on the engine runs.
//!
//! `assets/` of the working directory wins when it has the default scene (a checkout), then
//! the source tree the binary was built from. A binary copied elsewhere has neither: its
//! own copy of the files, embedded at compile time, is written once to the cache directory
//! (each file to a temporary name, then renamed) and used from there, so every command can
//! keep reading assets as files.
//!
//! `SSBVB_ASSETS_DIR` overrides the search: a folder to use, or `bundled` for the embedded
//! copy even where a source tree exists (how the tests check a relocated binary).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Every bundled file, relative to `assets/`, with its contents.
const FILES: &[(&str, &[u8])] = &[
    (
        "scenes/default.ron",
        include_bytes!("../../../assets/scenes/default.ron"),
    ),
    (
        "pipelines/ssbvb_unique.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_unique.ron"),
    ),
    (
        "pipelines/ssbvb_splat.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_splat.ron"),
    ),
    (
        "pipelines/ssbvb_pixel.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_pixel.ron"),
    ),
    (
        "pipelines/ssbvb_direct.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_direct.ron"),
    ),
    (
        "pipelines/ssbvb_compute.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_compute.ron"),
    ),
    (
        "pipelines/ssbvb_all_compute.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_all_compute.ron"),
    ),
    (
        "pipelines/ssbvb_aa.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_aa.ron"),
    ),
    (
        "pipelines/ssbvb_edge_aa.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_edge_aa.ron"),
    ),
    (
        "pipelines/ssbvb_flat.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_flat.ron"),
    ),
    (
        "pipelines/ssbvb_vct.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_vct.ron"),
    ),
    (
        "scenes/bunnies_64.ron",
        include_bytes!("../../../assets/scenes/bunnies_64.ron"),
    ),
    (
        "scenes/bunnies_4096.ron",
        include_bytes!("../../../assets/scenes/bunnies_4096.ron"),
    ),
    (
        "pipelines/ssbvb_embedded.ron",
        include_bytes!("../../../assets/pipelines/ssbvb_embedded.ron"),
    ),
    (
        "pipelines/dense_dda.ron",
        include_bytes!("../../../assets/pipelines/dense_dda.ron"),
    ),
    (
        "pipelines/octree.ron",
        include_bytes!("../../../assets/pipelines/octree.ron"),
    ),
    (
        "pipelines/esvo.ron",
        include_bytes!("../../../assets/pipelines/esvo.ron"),
    ),
    (
        "pipelines/cube_raster.ron",
        include_bytes!("../../../assets/pipelines/cube_raster.ron"),
    ),
    (
        "pipelines/rastavox.ron",
        include_bytes!("../../../assets/pipelines/rastavox.ron"),
    ),
    (
        "scenes/twisting_bunny.ron",
        include_bytes!("../../../assets/scenes/twisting_bunny.ron"),
    ),
    (
        "pipelines/volumetric.ron",
        include_bytes!("../../../assets/pipelines/volumetric.ron"),
    ),
    (
        "scenes/volumetric.ron",
        include_bytes!("../../../assets/scenes/volumetric.ron"),
    ),
    (
        "models/bunny.obj",
        include_bytes!("../../../assets/models/bunny.obj"),
    ),
];

/// The default scene, relative to the assets folder.
pub const DEFAULT_SCENE: &str = "scenes/default.ron";

fn is_assets_dir(dir: &Path) -> bool {
    dir.join(DEFAULT_SCENE).is_file()
}

/// The bundled asset folder (see the module docs).
pub fn assets_dir() -> PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let forced = std::env::var_os("SSBVB_ASSETS_DIR").filter(|v| !v.is_empty());
        match forced {
            Some(v) if v == "bundled" => return extract_or_warn(),
            Some(v) => return PathBuf::from(v),
            None => {}
        }
        let here = PathBuf::from("assets");
        if is_assets_dir(&here) {
            return here;
        }
        let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        if is_assets_dir(&source) {
            return source;
        }
        extract_or_warn()
    })
    .clone()
}

fn extract_or_warn() -> PathBuf {
    let cache = ssbvb_voxel::cache::default_cache_dir();
    match extract(&cache) {
        Ok(dir) => dir,
        Err(e) => {
            // Reads of the assets will fail and name the path; say why here once.
            log::warn!(
                "warning: cannot write the bundled assets under {}: {e}",
                cache.display()
            );
            bundle_dir(&cache)
        }
    }
}

/// The folder of this build's bundle under `cache` (named by the bundle's hash, so a newer
/// binary never reads an older bundle).
fn bundle_dir(cache: &Path) -> PathBuf {
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    for (name, bytes) in FILES {
        h.update(name.as_bytes());
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    }
    cache.join(format!("bundled-assets-{:016x}", h.digest()))
}

/// Writes every bundled file under `cache` (skipping those already there with the right
/// size) and returns the folder.
fn extract(cache: &Path) -> std::io::Result<PathBuf> {
    let dir = bundle_dir(cache);
    for (name, bytes) in FILES {
        let path = dir.join(name);
        if std::fs::metadata(&path).is_ok_and(|m| m.len() == bytes.len() as u64) {
            continue;
        }
        let parent = path.parent().unwrap_or(&dir);
        std::fs::create_dir_all(parent)?;
        let mut tmp = tempfile::NamedTempFile::new_in(parent)?;
        std::io::Write::write_all(&mut tmp, bytes)?;
        tmp.persist(&path).map_err(|e| e.error)?;
    }
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundle_matches_the_source_tree_and_extracts_completely() {
        let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        // Every pipeline of the source tree is bundled (the viewer lists them all).
        for e in std::fs::read_dir(source.join("pipelines")).unwrap() {
            let name = format!("pipelines/{}", e.unwrap().file_name().to_string_lossy());
            assert!(
                FILES.iter().any(|(n, _)| *n == name),
                "{name} is not bundled in the binary"
            );
        }
        let tmp = tempfile::tempdir().unwrap();
        let dir = extract(tmp.path()).unwrap();
        for (name, bytes) in FILES {
            assert_eq!(&std::fs::read(dir.join(name)).unwrap(), bytes, "{name}");
            assert_eq!(
                &std::fs::read(source.join(name)).unwrap(),
                bytes,
                "{name} differs from the source tree"
            );
        }
        assert!(is_assets_dir(&dir));
        // A second extraction finds everything in place.
        assert_eq!(extract(tmp.path()).unwrap(), dir);
    }
}
