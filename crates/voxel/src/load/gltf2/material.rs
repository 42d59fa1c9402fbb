//! Materials: base colour factors and base colour textures (embedded or external images).

use super::Builder;
use super::buffers::{UriError, read_uri};
use crate::load::common::decode_texture;
use crate::load::error::LoadError;
use crate::model::{Material, Texture};

impl Builder<'_> {
    /// The `mesh.materials` index of a glTF material, converting it on first use.
    pub(super) fn material(&mut self, index: Option<usize>) -> Result<u32, LoadError> {
        if let Some(&m) = self.materials.get(&index) {
            return Ok(m);
        }
        let material = match index {
            // The glTF default material is white (not the project's grey default).
            None => Material {
                base_color: [1.0; 4],
                base_color_texture: None,
            },
            Some(i) => {
                let root = self.root;
                let m = root
                    .materials
                    .get(i)
                    .ok_or_else(|| self.err(format!("material {i} does not exist")))?;
                let pbr = &m.pbr_metallic_roughness;
                let texture = match &pbr.base_color_texture {
                    Some(info) => {
                        if info.tex_coord != 0 {
                            self.warn(format!(
                                "material {i}: base colour texture uses TEXCOORD_{}; only TEXCOORD_0 is read",
                                info.tex_coord
                            ));
                        }
                        self.texture(info.index.value())
                    }
                    None => None,
                };
                Material {
                    base_color: pbr.base_color_factor.0.map(|c| {
                        if c.is_finite() {
                            c.clamp(0.0, 1.0)
                        } else {
                            1.0
                        }
                    }),
                    base_color_texture: texture,
                }
            }
        };
        let slot = self.mesh.materials.len() as u32;
        self.mesh.materials.push(material);
        self.materials.insert(index, slot);
        Ok(slot)
    }

    /// Decodes the image of glTF texture `texture_index`; failures are warnings.
    fn texture(&mut self, texture_index: usize) -> Option<Texture> {
        let root = self.root;
        let Some(image_index) = root.textures.get(texture_index).map(|t| t.source.value()) else {
            self.warn(format!("texture {texture_index} does not exist"));
            return None;
        };
        if let Some(t) = self.textures.get(&image_index) {
            return t.clone();
        }
        let result = self
            .image_bytes(image_index)
            .and_then(|bytes| decode_texture(&bytes));
        let texture = match result {
            Ok(t) => Some(t),
            Err(e) => {
                self.warn(format!("image {image_index} not loaded: {e}"));
                None
            }
        };
        self.textures.insert(image_index, texture.clone());
        texture
    }

    fn image_bytes(&self, image_index: usize) -> Result<Vec<u8>, String> {
        let image = self
            .root
            .images
            .get(image_index)
            .ok_or("the image does not exist")?;
        if let Some(view) = image.buffer_view {
            return self
                .view_bytes(view.value())
                .map(<[u8]>::to_vec)
                .map_err(|e| e.to_string());
        }
        match &image.uri {
            Some(uri) => read_uri(uri, self.path, self.base_dir).map_err(UriError::describe),
            None => Err("the image has neither a uri nor a bufferView".into()),
        }
    }
}
