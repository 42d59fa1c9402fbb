//! Model loaders: Wavefront OBJ (+ MTL), PLY, glTF 2.0 / GLB, MagicaVoxel `.vox`, and the
//! project's raw dense grid (`.raw`, see [`write_raw`] for the format).
//!
//! Every loader parses untrusted bytes: nothing here panics on any input, every count a
//! file declares is checked against the bytes actually present and against the limits
//! below *before* anything is allocated from it, and every error names the file and, where
//! possible, the line (text formats) or byte offset (binary formats).
//!
//! # Conventions (what the loaders hand downstream)
//!
//! * **Units and axes of meshes** are the file's own; nothing is rescaled or re-oriented
//!   (glTF node transforms are applied, glTF is already Y-up).
//! * **MagicaVoxel is Z-up**; `.vox` voxels are converted to the renderer's Y-up with the
//!   proper rotation `(x, y, z) ↦ (x, z, −y)`. A unit cube `[p, p+1]` maps to the cube
//!   whose minimum corner is `(p.x, p.z, −p.y − 1)`.
//! * **Colours are linear.** Vertex colours of OBJ and PLY files and `.vox` palettes are
//!   sRGB-encoded display values in those ecosystems, so they are decoded to linear. glTF
//!   `COLOR_0` and `baseColorFactor` are linear by specification; MTL `Kd` is taken as a
//!   linear reflectance (as Blender's importer does). Textures (MTL `map_Kd`, glTF base
//!   colour textures) are sRGB images and are stored as *linear* RGBA8 (alpha untouched):
//!   see [`Texture`](crate::model::Texture).
//! * **Colour composition** follows glTF: the colour of a surface point is
//!   `material.base_color × texture(uv) × vertex colour`, each factor optional. Meshes whose
//!   files have no materials (PLY, OBJ without `usemtl`) get an empty `materials` list.
//! * **Triangles**: polygons are fan-triangulated; zero-area triangles are kept (the
//!   voxelizer handles them). Triangle strips (PLY `tristrips`, glTF `TRIANGLE_STRIP`)
//!   alternate winding as usual; strip triangles that repeat an *index* are dropped, since
//!   they are stitching artefacts of the strip encoding rather than surface.

mod common;
mod error;
mod gltf2;
mod obj;
mod ply;
mod raw;
mod vox;

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::model::{Mesh, Model, VoxelModel};
use common::{SOURCES, read_file};

pub use common::{
    MAX_FILE_BYTES, MAX_RAW_DIM, MAX_TRIANGLES, MAX_VERTICES, MAX_VOXELS, srgb_to_linear,
};
pub use error::LoadError;

/// The file formats this module reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// Wavefront OBJ (with MTL material libraries).
    Obj,
    /// Stanford PLY, ASCII or binary (either endianness).
    Ply,
    /// glTF 2.0 JSON (`.gltf`), with external or data-URI buffers.
    Gltf,
    /// glTF 2.0 binary container (`.glb`).
    Glb,
    /// MagicaVoxel `.vox`.
    Vox,
    /// The raw dense grid of [`write_raw`].
    Raw,
}

impl Format {
    /// The format of a file extension (without the dot, case-insensitive).
    pub fn from_extension(ext: &str) -> Option<Self> {
        match ext.to_ascii_lowercase().as_str() {
            "obj" => Some(Format::Obj),
            "ply" => Some(Format::Ply),
            "gltf" => Some(Format::Gltf),
            "glb" => Some(Format::Glb),
            "vox" => Some(Format::Vox),
            "raw" => Some(Format::Raw),
            _ => None,
        }
    }

    /// The format of a path, from its extension.
    pub fn from_path(path: &Path) -> Option<Self> {
        path.extension()
            .and_then(|e| e.to_str())
            .and_then(Self::from_extension)
    }

    /// Guesses the format from the first bytes of a file (its magic number, or for the
    /// text formats what their first statement looks like). Reading 512 bytes is plenty.
    pub fn sniff(head: &[u8]) -> Option<Self> {
        if head.starts_with(b"glTF") {
            return Some(Format::Glb);
        }
        if head.starts_with(b"VOX ") {
            return Some(Format::Vox);
        }
        if head.starts_with(raw::MAGIC) {
            return Some(Format::Raw);
        }
        if head.starts_with(b"ply\n") || head.starts_with(b"ply\r\n") {
            return Some(Format::Ply);
        }
        let text = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
        let first = text
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .map(|i| &text[i..]);
        match first {
            Some(rest) if rest.starts_with(b"{") => Some(Format::Gltf),
            Some(_) if obj::looks_like_obj(text) => Some(Format::Obj),
            _ => None,
        }
    }

    /// Whether the format holds triangle meshes (as opposed to voxels).
    pub fn is_mesh(self) -> bool {
        matches!(self, Format::Obj | Format::Ply | Format::Gltf | Format::Glb)
    }
}

/// Options for [`load_model_with`] and [`load_from_bytes`].
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Forces a format instead of detecting it from the extension or content.
    pub format: Option<Format>,
    /// `.vox` only: load just this model (its index among the file's `SIZE`/`XYZI` pairs),
    /// in its own coordinates, ignoring the scene graph. `None` loads the whole scene
    /// (every instance placed by the scene graph, or every model at its own origin when
    /// the file has no scene graph, as for animation frames).
    pub vox_model: Option<usize>,
}

/// A loaded model together with the non-fatal problems met while loading it.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The model.
    pub model: Model,
    /// Human-readable warnings (a missing MTL library or texture, skipped primitives, ...),
    /// each naming the file concerned.
    pub warnings: Vec<String>,
    /// Every file the model depends on, the model file first: MTL libraries, textures,
    /// external glTF buffers and images, including those looked for and not found (adding
    /// one changes the model). The asset cache keys on their contents.
    pub sources: Vec<PathBuf>,
}

/// Loads any supported model, choosing the format by extension (case-insensitive) or, for
/// an unknown or missing extension, by content. Warnings are sent to the `log` crate.
pub fn load_model(path: &Path) -> Result<Model, LoadError> {
    let loaded = load_model_with(path, &LoadOptions::default())?;
    for w in &loaded.warnings {
        log::warn!("{w}");
    }
    Ok(loaded.model)
}

/// Loads a mesh format (OBJ, PLY, glTF, GLB); a voxel file is an
/// [`LoadError::UnsupportedFormat`] here.
pub fn load_mesh(path: &Path) -> Result<Mesh, LoadError> {
    let format = detect_format(path, None)?;
    if !format.is_mesh() {
        return Err(LoadError::UnsupportedFormat {
            path: path.to_path_buf(),
            ext: extension_of(path),
        });
    }
    match load_model(path)? {
        Model::Mesh(mesh) => Ok(mesh),
        // Unreachable by construction: a mesh format always yields a mesh.
        Model::Voxels(_) => Err(LoadError::parse(path, "expected a mesh, got voxels")),
    }
}

/// Loads the single model `model_index` of a MagicaVoxel file, in its own coordinates
/// (converted to Y-up, no scene-graph transform), e.g. one animation frame of `T-Rex.vox`.
pub fn load_vox_model(path: &Path, model_index: usize) -> Result<VoxelModel, LoadError> {
    let options = LoadOptions {
        format: Some(Format::Vox),
        vox_model: Some(model_index),
    };
    match load_model_with(path, &options)?.model {
        Model::Voxels(v) => Ok(v),
        Model::Mesh(_) => Err(LoadError::parse(path, "expected voxels, got a mesh")),
    }
}

/// Loads a model with options, returning the warnings instead of logging them.
pub fn load_model_with(path: &Path, options: &LoadOptions) -> Result<Loaded, LoadError> {
    let format = detect_format(path, options.format)?;
    if format == Format::Raw {
        // Raw grids can be far larger than anything else: stream them from disk.
        let voxels = raw::load_path(path)?;
        return Ok(Loaded {
            model: Model::Voxels(voxels),
            warnings: Vec::new(),
            sources: vec![path.to_path_buf()],
        });
    }
    // Collect the files this load touches (nested loads keep their outer list).
    let outer = SOURCES.with(|s| s.borrow_mut().replace(vec![path.to_path_buf()]));
    let result = load_main(path, format, options);
    let sources = SOURCES.with(|s| std::mem::replace(&mut *s.borrow_mut(), outer));
    let mut loaded = result?;
    loaded.sources = sources.unwrap_or_default();
    Ok(loaded)
}

fn load_main(path: &Path, format: Format, options: &LoadOptions) -> Result<Loaded, LoadError> {
    let bytes = read_file(path)?;
    let base_dir = path.parent().map(|p| {
        if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        }
    });
    load_from_bytes(&bytes, format, path, base_dir, options)
}

/// Parses a model held in memory.
///
/// `name` is only used in messages. `base_dir` is where files the model references (MTL
/// libraries, textures, external glTF buffers and images) are looked up; with `None` no
/// file is ever opened (missing MTL libraries and textures become warnings, external glTF
/// buffers an error), which makes this the entry point for fuzzing.
pub fn load_from_bytes(
    bytes: &[u8],
    format: Format,
    name: &Path,
    base_dir: Option<&Path>,
    options: &LoadOptions,
) -> Result<Loaded, LoadError> {
    let mut warnings = Vec::new();
    let model = match format {
        Format::Obj => Model::Mesh(obj::parse(bytes, name, base_dir, &mut warnings)?),
        Format::Ply => Model::Mesh(ply::parse(bytes, name, &mut warnings)?),
        Format::Gltf | Format::Glb => {
            Model::Mesh(gltf2::parse(bytes, name, base_dir, &mut warnings)?)
        }
        Format::Vox => Model::Voxels(vox::parse(bytes, name, options.vox_model, &mut warnings)?),
        Format::Raw => Model::Voxels(raw::parse_bytes(bytes, name)?),
    };
    match &model {
        Model::Mesh(m) => check_mesh(m, name)?,
        Model::Voxels(v) => {
            if v.voxels.is_empty() {
                return Err(LoadError::empty(name));
            }
        }
    }
    Ok(Loaded {
        model,
        warnings,
        // Filled in by `load_model_with`, which knows which files were read.
        sources: Vec::new(),
    })
}

/// Writes a raw dense grid atomically (a temporary file in the same folder, then a rename),
/// so a reader never sees a half-written file.
///
/// # Format
///
/// An ASCII header line `SSBVBRAW <nx> <ny> <nz>\n` (decimal, single spaces, each
/// dimension in `1..=4096`), followed by exactly `nx·ny·nz` bytes, one per cell, x fastest,
/// then y, then z. A byte `0` is empty; any other value is an occupied voxel whose colour is
/// the grey level `value / 255` (sRGB-encoded, decoded to linear on load). Cell `(x, y, z)`
/// is the unit cube `[x, x+1] × [y, y+1] × [z, z+1]`; the grid is Y-up like the renderer.
pub fn write_raw(path: &Path, nx: u32, ny: u32, nz: u32, cells: &[u8]) -> Result<(), LoadError> {
    let expected = raw::checked_cells(path, nx, ny, nz)?;
    if cells.len() as u64 != expected {
        return Err(LoadError::parse(
            path,
            format!(
                "write_raw: {nx}×{ny}×{nz} grid needs {expected} cells, got {}",
                cells.len()
            ),
        ));
    }
    let header = format!("SSBVBRAW {nx} {ny} {nz}\n");
    write_atomically(path, &[header.as_bytes(), cells])
}

/// Writes `parts` to a unique temporary file beside `path`, syncs it, and renames it over
/// `path`. The temporary file is removed if anything fails.
pub(crate) fn write_atomically(path: &Path, parts: &[&[u8]]) -> Result<(), LoadError> {
    write_atomically_with(path, |w| parts.iter().try_for_each(|p| w.write_all(p)))
}

/// [`write_atomically`] with the content streamed by `fill` through a buffered writer (a
/// large export is never held whole in memory).
pub(crate) fn write_atomically_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), LoadError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(
        ".{file_name}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| -> io::Result<()> {
        {
            // Closed before the rename.
            let f = fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&tmp)?;
            let mut w = io::BufWriter::with_capacity(1 << 20, f);
            fill(&mut w)?;
            w.flush()?;
            w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        }
        fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = fs::remove_file(&tmp);
        LoadError::io(path, e)
    })
}

/// The extension of a path as a lossy string (empty when there is none).
fn extension_of(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Forced format, else the extension, else a sniff of the first bytes.
fn detect_format(path: &Path, forced: Option<Format>) -> Result<Format, LoadError> {
    if let Some(f) = forced.or_else(|| Format::from_path(path)) {
        return Ok(f);
    }
    let mut head = [0u8; 512];
    let n = read_head(path, &mut head)?;
    Format::sniff(&head[..n]).ok_or_else(|| LoadError::UnsupportedFormat {
        path: path.to_path_buf(),
        ext: extension_of(path),
    })
}

fn read_head(path: &Path, buf: &mut [u8]) -> Result<usize, LoadError> {
    use std::io::Read;
    let mut f = fs::File::open(path).map_err(|e| LoadError::io(path, e))?;
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(LoadError::io(path, e)),
        }
    }
    Ok(n)
}

/// Verifies the [`Mesh`] invariants every loader promises, so that a loader bug surfaces
/// as an error rather than as an out-of-bounds access in the voxelizer.
fn check_mesh(mesh: &Mesh, path: &Path) -> Result<(), LoadError> {
    if mesh.triangles.is_empty() {
        return Err(LoadError::empty(path));
    }
    let n = mesh.positions.len();
    let bad_len = |len: usize| len != 0 && len != n;
    if bad_len(mesh.normals.len()) || bad_len(mesh.uvs.len()) || bad_len(mesh.colors.len()) {
        return Err(LoadError::parse(
            path,
            "internal error: vertex attribute lengths differ",
        ));
    }
    if mesh.triangles.iter().flatten().any(|&i| i as usize >= n) {
        return Err(LoadError::parse(
            path,
            "internal error: triangle index out of range",
        ));
    }
    if !mesh.triangle_materials.is_empty()
        && (mesh.triangle_materials.len() != mesh.triangles.len()
            || mesh
                .triangle_materials
                .iter()
                .any(|&m| m as usize >= mesh.materials.len()))
    {
        return Err(LoadError::parse(
            path,
            "internal error: bad triangle material",
        ));
    }
    Ok(())
}
