//! Prepared asset files used as models: a file in the cache format ([`super::write_cache`])
//! given where a model is expected (`ssbvb render edited.ssbvb`, a scene's `model:`,
//! `ssbvb export`) is read as it is, every level it holds, instead of being voxelized.
//! The viewer saves edited objects this way ([`write_asset_file`]), so the levels it saved
//! — each one the OR-merge of the edited finer one — are the levels drawn.
//!
//! Such a file is recognised by its first bytes ([`super::MAGIC`]), not its name. Its
//! source hash is the XXH3-128 of its finest point cloud: it names the content, and lets a
//! budgeted run page from the file as from any cache file.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use xxhash_rust::xxh3::xxh3_128;

use super::format::{CacheError, HEADER_BYTES, MAGIC, le_bytes};
use super::{read_cache, write_cache};
use crate::asset::VoxelAsset;

/// The file extension the viewer suggests for saved edits (any name is read by content).
pub const ASSET_FILE_EXTENSION: &str = "ssbvb";

/// What the header of a prepared asset file says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AssetFileHeader {
    /// The source hash the file was written with (what [`read_cache`] expects).
    pub source_hash: u128,
    /// Its finest level (it holds levels `0..=level`).
    pub level: u32,
}

/// The header of `path` when it is a prepared asset file (it starts with the cache's
/// magic), `None` when it is anything else (a model to voxelize). Only the header's place
/// is read here; [`read_asset_file`] checks everything.
pub fn asset_file_header(path: &Path) -> Result<Option<AssetFileHeader>, CacheError> {
    let mut file = File::open(path).map_err(|e| CacheError::io(path, e))?;
    let mut h = [0u8; HEADER_BYTES];
    let mut got = 0;
    while got < h.len() {
        match file.read(&mut h[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(CacheError::io(path, e)),
        }
    }
    if got < MAGIC.len() || h[..MAGIC.len()] != MAGIC {
        return Ok(None);
    }
    if got < HEADER_BYTES {
        return Err(CacheError::Truncated {
            path: path.to_path_buf(),
            what: "header".into(),
        });
    }
    let source_hash = u128::from_le_bytes(h[16..32].try_into().unwrap_or_default());
    let level = u32::from_le_bytes(h[32..36].try_into().unwrap_or_default());
    Ok(Some(AssetFileHeader { source_hash, level }))
}

/// Reads the prepared asset file `path` (fully checked, as a cache file is), keeping
/// levels `0..=level` when `level` is given. A level finer than the file holds is a
/// [`CacheError::LevelMismatch`] naming both.
pub fn read_asset_file(
    path: &Path,
    level: Option<u32>,
) -> Result<(VoxelAsset, AssetFileHeader), CacheError> {
    let Some(header) = asset_file_header(path)? else {
        return Err(CacheError::BadMagic {
            path: path.to_path_buf(),
        });
    };
    if let Some(l) = level.filter(|&l| l > header.level) {
        return Err(CacheError::LevelMismatch {
            path: path.to_path_buf(),
            found: header.level,
            expected: l,
        });
    }
    let mut asset = read_cache(path, header.source_hash, header.level)?;
    if let Some(l) = level {
        asset.lods.truncate(l as usize + 1);
    }
    Ok((asset, header))
}

/// Writes `asset` (levels `0..=finest`) to `path` as a prepared asset file, atomically
/// (a temporary file renamed over `path`: a failed write leaves the previous file whole).
/// Returns the header written.
pub fn write_asset_file(path: &Path, asset: &VoxelAsset) -> Result<AssetFileHeader, CacheError> {
    let Some(finest) = asset.lods.last() else {
        return Err(CacheError::corrupt(path, "an asset without levels"));
    };
    let header = AssetFileHeader {
        source_hash: xxh3_128(&le_bytes(&finest.point_cloud.voxels)),
        level: finest.level,
    };
    write_cache(path, asset, header.source_hash, header.level)?;
    Ok(header)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prepare::prepare_asset;
    use crate::prepare::tests::tetra;
    use crate::progress::NoProgress;

    #[test]
    fn an_asset_file_reads_back_whole_or_cut_to_a_coarser_level() {
        let dir = tempfile::tempdir().unwrap();
        let (asset, _) = prepare_asset(&tetra(), 5, &NoProgress).unwrap();
        let path = dir.path().join("t.ssbvb");
        let header = write_asset_file(&path, &asset).unwrap();
        assert_eq!(header.level, 5);
        assert_eq!(asset_file_header(&path).unwrap(), Some(header));
        let (back, _) = read_asset_file(&path, None).unwrap();
        assert_eq!(back, asset);
        let (cut, _) = read_asset_file(&path, Some(3)).unwrap();
        assert_eq!(cut.lods.len(), 4);
        assert_eq!(cut.lods[..], asset.lods[..4]);
        match read_asset_file(&path, Some(6)) {
            Err(CacheError::LevelMismatch {
                found: 5,
                expected: 6,
                ..
            }) => {}
            other => panic!("{other:?}"),
        }
        // A model file is not an asset file; a damaged asset file is an error, not a model.
        let obj = dir.path().join("m.obj");
        std::fs::write(&obj, "v 0 0 0\n").unwrap();
        assert_eq!(asset_file_header(&obj).unwrap(), None);
        let mut bytes = std::fs::read(&path).unwrap();
        let n = bytes.len();
        bytes[n - 3] ^= 0x40;
        std::fs::write(&path, &bytes).unwrap();
        assert!(matches!(
            read_asset_file(&path, None),
            Err(CacheError::Checksum { .. })
        ));
        std::fs::write(&path, &bytes[..40]).unwrap();
        assert!(matches!(
            asset_file_header(&path),
            Err(CacheError::Truncated { .. })
        ));
    }
}
