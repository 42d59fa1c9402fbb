//! MTL libraries: `newmtl`, `Kd`, `d` / `Tr` and `map_Kd`, and the textures they name.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::text::{Lines, numbers, parse_f32, split_keyword, tokens, trim};
use crate::load::common::{decode_texture, read_file, record_source};
use crate::load::error::LoadError;
use crate::model::{Material, Texture};

/// One `newmtl` of an MTL library (only what the voxelizer uses).
pub(super) struct MtlMaterial {
    diffuse: Option<[f32; 3]>,
    alpha: f32,
    /// `map_Kd`, already resolved against the library's folder.
    texture: Option<PathBuf>,
}

impl MtlMaterial {
    pub(super) fn to_material(
        &self,
        textures: &mut TextureCache,
        warnings: &mut Vec<String>,
    ) -> Material {
        let texture = self
            .texture
            .as_ref()
            .and_then(|p| textures.get(p, warnings));
        // MTL's `map_Kd` is multiplied by `Kd`; without `Kd` the texture alone is meant, so
        // the factor is white, and without either we keep the project's default grey.
        let rgb = match (self.diffuse, &texture) {
            (Some(kd), _) => kd,
            (None, Some(_)) => [1.0; 3],
            (None, None) => {
                let d = Material::default().base_color;
                [d[0], d[1], d[2]]
            }
        };
        Material {
            base_color: [rgb[0], rgb[1], rgb[2], self.alpha],
            base_color_texture: texture,
        }
    }
}

#[derive(Default)]
pub(super) struct TextureCache {
    loaded: HashMap<PathBuf, Option<Texture>>,
}

impl TextureCache {
    fn get(&mut self, path: &Path, warnings: &mut Vec<String>) -> Option<Texture> {
        self.loaded
            .entry(path.to_path_buf())
            .or_insert_with(|| {
                let result = read_file(path)
                    .map_err(|e| e.to_string())
                    .and_then(|bytes| {
                        decode_texture(&bytes).map_err(|e| format!("{}: {e}", path.display()))
                    });
                match result {
                    Ok(t) => Some(t),
                    Err(e) => {
                        warnings.push(format!("texture not loaded: {e}"));
                        None
                    }
                }
            })
            .clone()
    }
}

/// Finds a file named in the model, tolerating Windows separators.
fn resolve_file(dir: &Path, name: &str) -> Option<PathBuf> {
    let direct = dir.join(name);
    if direct.is_file() {
        return Some(direct);
    }
    let slashed = dir.join(name.replace('\\', "/"));
    if slashed.is_file() {
        return Some(slashed);
    }
    // Not there: creating it later changes the model.
    record_source(&direct);
    None
}

/// Loads every `mtllib` (later definitions of a name win, as in most viewers).
pub(super) fn load_libraries(
    mtllibs: &[(usize, String)],
    obj_path: &Path,
    base_dir: Option<&Path>,
    warnings: &mut Vec<String>,
) -> Result<HashMap<String, MtlMaterial>, LoadError> {
    let mut library = HashMap::new();
    let Some(dir) = base_dir else {
        if !mtllibs.is_empty() {
            let names: Vec<&str> = mtllibs.iter().map(|(_, n)| n.as_str()).collect();
            warnings.push(format!(
                "{}: MTL libraries not loaded (no base folder given): {}",
                obj_path.display(),
                names.join(", ")
            ));
        }
        return Ok(library);
    };
    for (line, names) in mtllibs {
        // A library name may contain spaces; otherwise the line lists several libraries.
        let files: Vec<PathBuf> = match resolve_file(dir, names) {
            Some(p) => vec![p],
            None => names
                .split_ascii_whitespace()
                .filter_map(|n| {
                    let found = resolve_file(dir, n);
                    if found.is_none() {
                        warnings.push(format!(
                            "{}:{line}: MTL library {n:?} not found in {}",
                            obj_path.display(),
                            dir.display()
                        ));
                    }
                    found
                })
                .collect(),
        };
        for file in files {
            let bytes = read_file(&file)?;
            let mtl_dir = file.parent().unwrap_or(dir).to_path_buf();
            parse_mtl(&bytes, &file, &mtl_dir, &mut library, warnings)?;
        }
    }
    Ok(library)
}

/// Parses an MTL library into `library`.
fn parse_mtl(
    bytes: &[u8],
    path: &Path,
    dir: &Path,
    library: &mut HashMap<String, MtlMaterial>,
    warnings: &mut Vec<String>,
) -> Result<(), LoadError> {
    let mut current: Option<(String, MtlMaterial)> = None;
    for (line_no, line) in Lines::new(bytes) {
        let line = trim(&line);
        if line.is_empty() || line[0] == b'#' {
            continue;
        }
        let (keyword, rest) = split_keyword(line);
        if keyword == b"newmtl" {
            if let Some((name, m)) = current.take() {
                library.insert(name, m);
            }
            let name = String::from_utf8_lossy(trim(rest)).into_owned();
            current = Some((
                name,
                MtlMaterial {
                    diffuse: None,
                    alpha: 1.0,
                    texture: None,
                },
            ));
            continue;
        }
        let Some((_, m)) = current.as_mut() else {
            continue; // statements before the first `newmtl` belong to no material
        };
        match keyword {
            b"Kd" => {
                let mut v = [0f32; 3];
                let n = numbers(rest, &mut v, path, line_no)?;
                // `Kd r` is a grey; `Kd r g b` a colour; `Kd spectral ...` / `Kd xyz ...`
                // are not numbers and were rejected by `numbers`.
                let rgb = match n {
                    1 => [v[0]; 3],
                    3 => v,
                    _ => {
                        return Err(LoadError::at_line(
                            path,
                            line_no,
                            format!("`Kd` needs 1 or 3 numbers, found {n}"),
                        ));
                    }
                };
                m.diffuse = Some(rgb.map(|c| c.clamp(0.0, 1.0)));
            }
            b"d" | b"Tr" => {
                let mut v = [0f32; 1];
                // `d -halo 0.5` exists in the spec: skip the option.
                let rest = trim(rest);
                let rest = rest.strip_prefix(b"-halo").unwrap_or(rest);
                let n = numbers(rest, &mut v, path, line_no)?;
                if n != 1 {
                    return Err(LoadError::at_line(path, line_no, "expected one number"));
                }
                let value = v[0].clamp(0.0, 1.0);
                m.alpha = if keyword == b"d" { value } else { 1.0 - value };
            }
            b"map_Kd" => {
                let name = texture_file_name(rest);
                if name.is_empty() {
                    return Err(LoadError::at_line(path, line_no, "`map_Kd` names no file"));
                }
                match resolve_file(dir, &name) {
                    Some(p) => m.texture = Some(p),
                    None => warnings.push(format!(
                        "{}:{line_no}: texture {name:?} not found in {}",
                        path.display(),
                        dir.display()
                    )),
                }
            }
            _ => {}
        }
    }
    if let Some((name, m)) = current {
        library.insert(name, m);
    }
    Ok(())
}

/// The file name of a `map_*` statement, after its options (`-s 1 1 1`, `-clamp on`, ...).
fn texture_file_name(rest: &[u8]) -> String {
    let toks: Vec<&[u8]> = tokens(rest).collect();
    let mut i = 0;
    while i < toks.len() && toks[i].first() == Some(&b'-') {
        // Options take up to this many arguments; numeric ones are skipped while they
        // parse as numbers, so `-s 2` and `-s 2 2 2` both work.
        let max_args = match toks[i] {
            b"-o" | b"-s" | b"-t" => 3,
            b"-mm" => 2,
            b"-blendu" | b"-blendv" | b"-cc" | b"-clamp" | b"-texres" | b"-imfchan" | b"-type"
            | b"-bm" | b"-boost" | b"-colorspace" => 1,
            _ => 0,
        };
        i += 1;
        let mut taken = 0;
        while taken < max_args && i < toks.len() - 1 {
            let t = toks[i];
            let is_arg = parse_f32(t).is_some()
                || matches!(t, b"on" | b"off" | b"r" | b"g" | b"b" | b"m" | b"l" | b"z")
                || max_args == 1;
            if !is_arg {
                break;
            }
            i += 1;
            taken += 1;
        }
    }
    let name: Vec<&[u8]> = toks.get(i..).unwrap_or_default().to_vec();
    String::from_utf8_lossy(&name.join(&b' ')).into_owned()
}
