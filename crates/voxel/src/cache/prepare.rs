//! [`load_or_prepare`]: the asset of a model file from the cache, or prepared from the
//! source and written to the cache, with what was done and why.

use std::io;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::deps::{self, Dependency};
use super::format::{CacheError, FORMAT_VERSION};
use super::{
    asset_file_header, cache_file_name, default_cache_dir, hash_source, read_asset_file,
    read_cache, write_cache,
};
use crate::asset::VoxelAsset;
use crate::load::{LoadError, LoadOptions, load_model_with};
use crate::model::Model;
use crate::prepare::{
    DEFAULT_MAX_LEVEL, PrepareStats, PrepareToFileError, REGION_LOG, prepare_asset,
    prepare_mesh_to_cache,
};
use crate::progress::Progress;
use crate::voxelize::VoxelizeError;

/// Whether an asset came from the cache or was rebuilt, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum CacheStatus {
    /// Read from a valid cache file.
    Hit,
    /// The model file is itself a prepared asset file (a viewer's save), read as it is.
    AssetFile,
    /// Prepared from the source (the reason says why the cache was not used).
    Rebuilt {
        /// Why: "cache missing", "cache corrupt (checksum mismatch in section …)", …
        reason: String,
    },
}

/// What [`load_or_prepare`] did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PrepareOutcome {
    /// The cache file read or written.
    pub cache_path: PathBuf,
    /// The source key the cache file was written with (model and dependency hashes: what
    /// [`super::read_cache`] expects).
    #[serde(skip)]
    pub cache_key: u128,
    /// Hit or rebuilt (with the reason).
    pub status: CacheStatus,
    /// Preparation statistics when the asset was rebuilt.
    pub stats: Option<PrepareStats>,
    /// Set when the rebuilt asset could not be written to the cache (the asset is still
    /// returned; the next run rebuilds again).
    pub cache_write_error: Option<String>,
    /// What the model's load could not do (a missing MTL library or texture, an image that
    /// does not decode), each line naming its file; kept beside the cache file, so a cache
    /// hit says them again.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

impl std::fmt::Display for PrepareOutcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.status {
            CacheStatus::Hit => write!(f, "cache hit ({})", self.cache_path.display())?,
            CacheStatus::AssetFile => write!(
                f,
                "prepared asset file, read as it is ({})",
                self.cache_path.display()
            )?,
            CacheStatus::Rebuilt { reason } => {
                write!(f, "{reason}, rebuilt ({})", self.cache_path.display())?
            }
        }
        if let Some(e) = &self.cache_write_error {
            write!(f, "; cache not written: {e}")?;
        }
        Ok(())
    }
}

/// Why [`load_or_prepare`] failed.
#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    /// The model could not be loaded.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The model could not be voxelized.
    #[error("{}: {error}", .path.display())]
    Voxelize {
        /// The model file.
        path: PathBuf,
        /// What went wrong.
        error: VoxelizeError,
    },
    /// The source file could not be read for hashing.
    #[error(transparent)]
    Cache(#[from] CacheError),
    /// A prepared asset file asked for at a level finer than it holds.
    #[error(
        "{}: a prepared asset file of levels 0..={holds}; level {asked} is finer than it \
         holds (ask for level {holds} or coarser)",
        .path.display()
    )]
    AssetLevel {
        /// The file.
        path: PathBuf,
        /// Its finest level.
        holds: u32,
        /// The level asked for.
        asked: u32,
    },
}

/// Returns the asset of `model_path` at `level`: read from the cache when a valid cache
/// file exists, otherwise prepared (with the default [`crate::prepare::PrepareOptions`])
/// and written to the cache. `cache_dir` defaults to [`default_cache_dir`]. A cache that
/// cannot be written is reported in the outcome, not an error.
///
/// The cache is keyed by the content of the model file and of every file its load read or
/// looked for (MTL libraries, textures, glTF buffers and images; see `deps.rs`), so editing
/// any of them rebuilds the asset, and the reason names the files that changed.
pub fn load_or_prepare(
    model_path: &Path,
    level: u32,
    cache_dir: Option<&Path>,
    progress: &dyn Progress,
) -> Result<(VoxelAsset, PrepareOutcome), PrepareError> {
    let (asset, outcome) = obtain(model_path, level, cache_dir, progress, false)?;
    match asset {
        Some(a) => Ok((a, outcome)),
        // `obtain` only leaves the asset out when asked to stream.
        None => Err(PrepareError::Cache(CacheError::corrupt(
            &outcome.cache_path,
            "prepared without an asset",
        ))),
    }
}

/// [`load_or_prepare`] for callers that need the cache file rather than the asset (e.g.
/// `ssbvb voxelize`): on a miss a mesh is prepared straight into the cache file, region
/// by region, without ever holding a level in memory
/// ([`crate::prepare::prepare_mesh_to_cache`]), and no asset is returned; a hit, or a
/// voxel model, returns the asset as [`load_or_prepare`] does. The cache file must be
/// writable here: it is where the result goes.
pub fn prepare_into_cache(
    model_path: &Path,
    level: u32,
    cache_dir: Option<&Path>,
    progress: &dyn Progress,
) -> Result<(Option<VoxelAsset>, PrepareOutcome), PrepareError> {
    obtain(model_path, level, cache_dir, progress, true)
}

fn obtain(
    model_path: &Path,
    level: u32,
    cache_dir: Option<&Path>,
    progress: &dyn Progress,
    stream: bool,
) -> Result<(Option<VoxelAsset>, PrepareOutcome), PrepareError> {
    if let Some(found) = asset_file(model_path, level)? {
        return Ok(found);
    }
    let model_hash = hash_source(model_path)?;
    let dir = cache_dir.map_or_else(default_cache_dir, Path::to_path_buf);
    let list = deps::list_path(&dir, model_hash);
    let reason = match deps::read_list(&list) {
        Some(recorded) => {
            let (changed, now) = deps::changes(&recorded);
            let key = deps::combined_key(model_hash, &now);
            let cache_path = dir.join(cache_file_name(key, level));
            match read_cache(&cache_path, key, level) {
                Ok(asset) => {
                    let outcome = PrepareOutcome {
                        cache_path,
                        cache_key: key,
                        status: CacheStatus::Hit,
                        stats: None,
                        cache_write_error: None,
                        warnings: read_warnings(&dir, key),
                    };
                    return Ok((Some(asset), outcome));
                }
                Err(_) if !changed.is_empty() => format!(
                    "changed since the cache was written: {}",
                    changed
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                Err(e) => e.rebuild_reason(),
            }
        }
        None => "cache missing".to_string(),
    };
    let loaded = load_model_with(model_path, &LoadOptions::default())?;
    let warnings = loaded.warnings.clone();
    // The model file itself is the first source; its hash is the list's name.
    let now: Vec<Dependency> = loaded
        .sources
        .iter()
        .skip(1)
        .map(|p| Dependency::now(p))
        .collect();
    let key = deps::combined_key(model_hash, &now);
    let cache_path = dir.join(cache_file_name(key, level));
    if let (true, Model::Mesh(mesh)) = (stream, &loaded.model) {
        check_level(model_path, level)?;
        let stats = prepare_mesh_to_cache(mesh, level, REGION_LOG, &cache_path, key, progress)
            .map_err(|e| match e {
                PrepareToFileError::Voxelize(error) => PrepareError::Voxelize {
                    path: model_path.to_path_buf(),
                    error,
                },
                PrepareToFileError::Cache(e) => PrepareError::Cache(e),
            })?;
        deps::write_list(&list, &now).map_err(|e| CacheError::io(&list, e))?;
        write_warnings(&dir, key, &warnings).map_err(|e| CacheError::io(&dir, e))?;
        let outcome = PrepareOutcome {
            cache_path,
            cache_key: key,
            status: CacheStatus::Rebuilt { reason },
            stats: Some(stats),
            cache_write_error: None,
            warnings,
        };
        return Ok((None, outcome));
    }
    let (asset, stats) =
        prepare_asset(&loaded.model, level, progress).map_err(|error| PrepareError::Voxelize {
            path: model_path.to_path_buf(),
            error,
        })?;
    drop(loaded);
    let cache_write_error = write_cache(&cache_path, &asset, key, level)
        .and_then(|()| deps::write_list(&list, &now).map_err(|e| CacheError::io(&list, e)))
        .and_then(|()| write_warnings(&dir, key, &warnings).map_err(|e| CacheError::io(&dir, e)))
        .err()
        .map(|e| e.to_string());
    let outcome = PrepareOutcome {
        cache_path,
        cache_key: key,
        status: CacheStatus::Rebuilt { reason },
        stats: Some(stats),
        cache_write_error,
        warnings,
    };
    Ok((Some(asset), outcome))
}

/// The asset of `model_path` when it is a prepared asset file (levels `0..=level` of it),
/// `None` when it is a model to prepare.
fn asset_file(
    model_path: &Path,
    level: u32,
) -> Result<Option<(Option<VoxelAsset>, PrepareOutcome)>, PrepareError> {
    let Some(found) = asset_file_header(model_path)? else {
        return Ok(None);
    };
    if level > found.level {
        return Err(PrepareError::AssetLevel {
            path: model_path.to_path_buf(),
            holds: found.level,
            asked: level,
        });
    }
    let (asset, header) = read_asset_file(model_path, Some(level))?;
    let outcome = PrepareOutcome {
        cache_path: model_path.to_path_buf(),
        cache_key: header.source_hash,
        status: CacheStatus::AssetFile,
        stats: None,
        // A budgeted run at a level coarser than the file's finest cannot page from the
        // file (`PageFile::open` says so) and streams from memory.
        cache_write_error: None,
        warnings: Vec::new(),
    };
    Ok(Some((Some(asset), outcome)))
}

/// The warnings file of cache key `key`: one warning per line (line breaks inside a
/// warning become spaces).
fn warnings_path(dir: &Path, key: u128) -> PathBuf {
    dir.join(format!("{key:032x}.warnings"))
}

/// The warnings recorded with cache key `key` (none when the file is missing).
fn read_warnings(dir: &Path, key: u128) -> Vec<String> {
    std::fs::read_to_string(warnings_path(dir, key))
        .map(|t| t.lines().map(str::to_string).collect())
        .unwrap_or_default()
}

/// Records the load's warnings for cache key `key` (temporary file, then renamed); none
/// removes the file.
fn write_warnings(dir: &Path, key: u128, warnings: &[String]) -> io::Result<()> {
    let path = warnings_path(dir, key);
    if warnings.is_empty() {
        return match std::fs::remove_file(&path) {
            Err(e) if e.kind() != io::ErrorKind::NotFound => Err(e),
            _ => Ok(()),
        };
    }
    let text: String = warnings
        .iter()
        .map(|w| w.replace(['\n', '\r'], " ") + "\n")
        .collect();
    std::fs::create_dir_all(dir)?;
    let mut tmp = tempfile::NamedTempFile::new_in(dir)?;
    io::Write::write_all(&mut tmp, text.as_bytes())?;
    tmp.persist(&path).map_err(|e| e.error)?;
    Ok(())
}

/// The level limit [`prepare_asset`] applies, for the streaming path that bypasses it.
fn check_level(model_path: &Path, level: u32) -> Result<(), PrepareError> {
    let max = DEFAULT_MAX_LEVEL.min(crate::asset::MAX_LEVEL);
    if level > max {
        return Err(PrepareError::Voxelize {
            path: model_path.to_path_buf(),
            error: VoxelizeError::LevelTooHigh { level, max },
        });
    }
    Ok(())
}

impl CacheError {
    /// Short description used in rebuild reasons ("cache missing", "cache corrupt (…)").
    fn rebuild_reason(&self) -> String {
        match self {
            CacheError::Io { error, .. } if error.kind() == io::ErrorKind::NotFound => {
                "cache missing".into()
            }
            CacheError::Io { error, .. } => format!("cache unreadable ({error})"),
            CacheError::BadMagic { .. } => "cache corrupt (bad magic)".into(),
            CacheError::UnsupportedVersion { found, .. } => {
                format!("cache from format version {found} (this build writes {FORMAT_VERSION})")
            }
            CacheError::SourceMismatch { .. } => "cache stale (source file changed)".into(),
            CacheError::LevelMismatch { found, .. } => format!("cache holds level {found}"),
            CacheError::Truncated { what, .. } => format!("cache corrupt (truncated in {what})"),
            CacheError::Checksum { section, .. } => {
                format!("cache corrupt (checksum mismatch in section {section})")
            }
            CacheError::Corrupt { reason, .. } => format!("cache corrupt ({reason})"),
        }
    }
}
