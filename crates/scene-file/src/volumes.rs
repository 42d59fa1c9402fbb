//! Translucent RGBA volumes in a scene file (volumetric billboards):
//!
//! ```ron
//! volumes: [
//!   (source: Cloud(seed: 3, density: 8.0, colour: (1.0, 1.0, 1.0)), edge: 64,
//!    instances: [(translation: (0.6, 0.3, -0.4), scale: 0.8)]),
//!   // A mesh voxelized with fractional coverage, or a VOX file with palette alpha.
//!   (source: Model("../models/bunny.obj"), edge: 64),
//! ]
//! ```

use serde::Deserialize;

use crate::instance::InstanceDesc;

/// Where a volume's texels come from.
#[derive(Debug, Deserialize, Clone, PartialEq)]
pub enum VolumeSource {
    /// A procedural cloud (deterministic for its seed).
    Cloud {
        /// Seed of the puff layout and the noise.
        #[serde(default = "one_u64")]
        seed: u64,
        /// Peak extinction per object-space unit.
        #[serde(default = "eight")]
        density: f32,
        /// Linear colour of the lit side.
        #[serde(default = "white")]
        colour: (f32, f32, f32),
    },
    /// A model file relative to the scene: a mesh (OBJ, PLY, glTF) voxelized with
    /// fractional coverage (alpha = covered fraction of each cell), or a VOX file whose
    /// palette alpha becomes the texels' (a palette without alpha gives opaque texels).
    Model(String),
}

fn one_u64() -> u64 {
    1
}
fn eight() -> f32 {
    8.0
}
fn white() -> (f32, f32, f32) {
    (1.0, 1.0, 1.0)
}
fn default_edge() -> u32 {
    64
}

/// The largest edge of a mesh-coverage volume (its voxelization level 7).
pub const MAX_MESH_VOLUME_EDGE: u32 = 128;
/// The largest edge of any volume.
pub const MAX_VOLUME_EDGE: u32 = 512;

/// One translucent volume.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct VolumeDesc {
    /// Its texels.
    pub source: VolumeSource,
    /// Texels along each axis of its finest level: a power of two, at most 512 (128 for a
    /// mesh).
    #[serde(default = "default_edge")]
    pub edge: u32,
    /// Placements (default: one at the origin). Object space is [-1, 1]³.
    #[serde(default)]
    pub instances: Option<Vec<InstanceDesc>>,
}

impl VolumeDesc {
    /// What is wrong with volume `i`, each naming its field.
    pub fn problems(&self, i: usize) -> Vec<String> {
        let mut out = Vec::new();
        if !(self.edge.is_power_of_two() && self.edge <= MAX_VOLUME_EDGE) {
            out.push(format!(
                "volumes[{i}].edge must be a power of two from 1 to {MAX_VOLUME_EDGE}, got {}",
                self.edge
            ));
        }
        match &self.source {
            VolumeSource::Cloud {
                density, colour, ..
            } => {
                if !(density.is_finite() && *density >= 0.0) {
                    out.push(format!(
                        "volumes[{i}].source: Cloud density must be a finite number >= 0, got \
                         {density}"
                    ));
                }
                if ![colour.0, colour.1, colour.2]
                    .iter()
                    .all(|c| c.is_finite() && (0.0..=1.0).contains(c))
                {
                    out.push(format!(
                        "volumes[{i}].source: Cloud colour must be three numbers from 0 to 1, \
                         got {colour:?}"
                    ));
                }
            }
            VolumeSource::Model(path) => {
                if path.is_empty() {
                    out.push(format!("volumes[{i}].source: Model needs a file"));
                }
            }
        }
        for (j, t) in self.instances.iter().flatten().enumerate() {
            if !(t.scale > 0.0 && t.scale.is_finite()) {
                out.push(format!(
                    "volumes[{i}].instances[{j}].scale must be a positive number, got {}",
                    t.scale
                ));
            }
            if ![
                t.translation.0,
                t.translation.1,
                t.translation.2,
                t.rotation_y_deg,
            ]
            .iter()
            .all(|v| v.is_finite())
            {
                out.push(format!(
                    "volumes[{i}].instances[{j}]: translation and rotation_y_deg must be finite"
                ));
            }
        }
        out
    }

    /// Its placements (one at the origin when none are written).
    pub fn placements(&self) -> Vec<InstanceDesc> {
        self.instances.clone().unwrap_or_else(|| {
            vec![InstanceDesc {
                translation: (0.0, 0.0, 0.0),
                rotation_y_deg: 0.0,
                scale: 1.0,
            }]
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::parse;

    #[test]
    fn volumes_parse_and_bad_values_name_their_field() {
        let ok = parse(
            "Scene(volumes: [(source: Cloud(seed: 2), edge: 32), (source: Model(\"b.obj\"))])",
            "s.ron",
        )
        .unwrap();
        assert_eq!(ok.volumes.len(), 2);
        assert_eq!(ok.volumes[1].edge, 64);
        for (text, want) in [
            (
                "Scene(volumes: [(source: Cloud(density: -1.0))])",
                "volumes[0].source: Cloud density must be a finite number >= 0, got -1",
            ),
            (
                "Scene(volumes: [(source: Cloud(), edge: 48)])",
                "volumes[0].edge must be a power of two from 1 to 512, got 48",
            ),
            (
                "Scene(volumes: [(source: Cloud(), instances: [(scale: 0.0)])])",
                "volumes[0].instances[0].scale must be a positive number, got 0",
            ),
            (
                "Scene(volumes: [(source: Cloud(colour: (1.0, 2.0, 0.0)))])",
                "volumes[0].source: Cloud colour must be three numbers from 0 to 1",
            ),
        ] {
            let e = parse(text, "s.ron").unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
        }
        // RON has no NaN literal for a density; an unknown field is a syntax error.
        let e = parse("Scene(volumes: [(source: Cloud(), fog: 1)])", "s.ron").unwrap_err();
        assert!(e.to_string().contains("fog"), "{e}");
    }
}
