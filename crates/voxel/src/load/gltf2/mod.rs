//! glTF 2.0 reader (`.gltf` with external or data-URI buffers, and `.glb`).
//!
//! The `gltf` crate deserialises the JSON document (its validation pass can panic, see
//! `parse_document`); every index into it and everything that touches binary data is
//! checked here: the GLB container, buffer URIs
//! (base64 data URIs and relative files), accessors (any component type, normalised or
//! not, strided views, sparse storage) and embedded images. `gltf::import` is not used
//! because its binary paths can panic on malformed input (GLB header length underflow,
//! unchecked buffer-view slicing for images, `unwrap` on percent-decoded URIs).
//!
//! Loaded: the default scene (or, without one, every scene; without scenes, every root
//! node), every mesh instance with its node's world matrix applied (normals with the
//! inverse transpose, winding flipped under mirroring transforms), primitives in
//! `TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN` modes (points and lines are skipped with
//! a warning), `POSITION`, `NORMAL`, `TEXCOORD_0`, `COLOR_0`, and each material's
//! `baseColorFactor` and base colour texture. Skins and morph targets are ignored (the bind
//! pose is loaded).
//!
//! Layout: the GLB container and the JSON document (`document`), buffers and URIs
//! (`buffers`), accessors (`accessor`, decoded into `values`), the scene walk and
//! primitives (`scene`), materials and textures (`material`).

mod accessor;
mod buffers;
mod document;
mod material;
mod scene;
mod values;

use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;

use gltf::json;

use super::error::LoadError;
use crate::model::{Mesh, Texture};
use buffers::load_buffers;
use document::{GLB_MAGIC, parse_document, split_glb};
use values::Values;

/// Parses a glTF or GLB file held in memory.
pub(super) fn parse(
    bytes: &[u8],
    path: &Path,
    base_dir: Option<&Path>,
    warnings: &mut Vec<String>,
) -> Result<Mesh, LoadError> {
    let is_glb = bytes.starts_with(GLB_MAGIC);
    let (json_bytes, json_offset, bin) = if is_glb {
        split_glb(bytes, path)?
    } else {
        (bytes, 0, None)
    };
    let root = parse_document(json_bytes, json_offset, is_glb, path)?;
    let buffers = load_buffers(&root, bin, path, base_dir)?;
    // Accessors without a buffer view are zero-filled and cost no bytes in the file: bound
    // them by the file size so that a tiny file cannot request gigabytes.
    let zero_fill_limit = (1u64 << 16).saturating_add((bytes.len() as u64).saturating_mul(16));
    let mut b = Builder {
        root: &root,
        buffers: &buffers,
        path,
        base_dir,
        zero_fill_limit,
        mesh: Mesh::default(),
        normals_missing: false,
        uvs_present: false,
        colors_present: false,
        materials: HashMap::new(),
        textures: HashMap::new(),
        accessor_cache: HashMap::new(),
        warnings,
    };
    b.load_scenes()?;
    b.finish()
}

/// The state of one load: the document, its buffers, and the mesh being built.
struct Builder<'a> {
    root: &'a json::Root,
    buffers: &'a [Vec<u8>],
    path: &'a Path,
    base_dir: Option<&'a Path>,
    zero_fill_limit: u64,
    mesh: Mesh,
    /// Some primitive had no normals: all normals are dropped at the end.
    normals_missing: bool,
    uvs_present: bool,
    colors_present: bool,
    /// glTF material index (`None`: the default material) → index in `mesh.materials`.
    materials: HashMap<Option<usize>, u32>,
    /// Decoded accessors by index.
    accessor_cache: HashMap<usize, Rc<Values>>,
    /// Decoded base colour textures per glTF image index (`None`: failed, warned once).
    textures: HashMap<usize, Option<Texture>>,
    warnings: &'a mut Vec<String>,
}

impl Builder<'_> {
    fn err(&self, message: String) -> LoadError {
        LoadError::parse(self.path, message)
    }

    fn warn(&mut self, message: String) {
        self.warnings
            .push(format!("{}: {message}", self.path.display()));
    }
}

#[cfg(test)]
mod tests {
    use super::buffers::{base64_decode, percent_decode};

    #[test]
    fn base64_round_trips_known_vectors() {
        assert_eq!(base64_decode("").unwrap(), b"");
        assert_eq!(base64_decode("Zg==").unwrap(), b"f");
        assert_eq!(base64_decode("Zm8=").unwrap(), b"fo");
        assert_eq!(base64_decode("Zm9v").unwrap(), b"foo");
        assert_eq!(base64_decode("Zm9vYg").unwrap(), b"foob");
        assert!(base64_decode("Zm9v!").is_err());
        assert!(base64_decode("Z").is_err());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("%FF"), None);
        assert_eq!(percent_decode("%2"), None);
    }
}
