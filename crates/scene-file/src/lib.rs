//! Scene files (`assets/scenes/*.ron`) as written: voxel objects, triangle objects, camera,
//! light, pipeline and GPU budget, parsed and checked field by field before anything is
//! loaded. Paths inside a scene are relative to the scene file; loading the models and
//! building the GPU scene is the frontend's job (`ssbvb` `scene_file.rs`).
//!
//! ```ron
//! Scene(
//!   pipeline: "../pipelines/ssbvb_unique.ron",
//!   camera: (position: (1.8, 1.2, 2.6), look_at: (0.0, -0.1, 0.0), fov_y: 45.0),
//!   objects: [
//!     (model: "../models/bunny.obj", level: 8, lod: Fixed(8),
//!      instances: [(translation: (0.0, 0.0, 0.0), rotation_y_deg: 0.0, scale: 1.0)]),
//!   ],
//!   triangles: [Plane(center: (0.0, -1.0, 0.0), half_size: 3.0, color: (0.55, 0.6, 0.55, 1.0))],
//! )
//! ```

mod instance;
pub mod volumes;

pub use instance::InstanceDesc;
pub use volumes::{VolumeDesc, VolumeSource};

use glam::DVec3;
use instance::one;
use serde::Deserialize;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::shading::Light;

/// Largest GPU budget a scene (or `--gpu-budget`) may ask for, in MiB (1 TiB).
pub const MAX_GPU_BUDGET_MIB: u64 = 1 << 20;

/// Why a scene file's text cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// Not RON of a `Scene`: a syntax error, an unknown field, a wrong type.
    #[error("{file}:{line}:{col}: {message}")]
    Syntax {
        /// The file as named by the caller.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// What RON reported.
        message: String,
    },
    /// Well-formed, with values the renderer cannot use (each naming its field).
    #[error("{file}: {}", problems.join("; "))]
    Invalid {
        /// The file.
        file: String,
        /// One line per bad field.
        problems: Vec<String>,
    },
}

/// Parses and checks a scene file's text; `file` names it in errors.
pub fn parse(text: &str, file: &str) -> Result<SceneFile, SceneError> {
    // Optional fields are written plainly (`lod: Fixed(8)`, not `lod: Some(Fixed(8))`).
    let options =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let scene: SceneFile = options.from_str(text).map_err(|e| SceneError::Syntax {
        file: file.to_string(),
        line: e.span.start.line,
        col: e.span.start.col,
        message: e.code.to_string(),
    })?;
    let problems = scene.problems();
    if problems.is_empty() {
        Ok(scene)
    } else {
        Err(SceneError::Invalid {
            file: file.to_string(),
            problems,
        })
    }
}

/// A scene file as written.
#[derive(Debug, Deserialize)]
#[serde(rename = "Scene", deny_unknown_fields)]
pub struct SceneFile {
    /// Pipeline file (relative to the scene file); absent: the bundled default pipeline,
    /// wherever the scene file lives.
    #[serde(default)]
    pub pipeline: Option<String>,
    /// The camera.
    #[serde(default)]
    pub camera: CameraDesc,
    /// The light (defaults to the reference's default light).
    #[serde(default)]
    pub light: Option<Light>,
    /// Voxel objects.
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
    /// Triangle objects.
    #[serde(default)]
    pub triangles: Vec<TriangleDesc>,
    /// Translucent RGBA volumes (drawn by a pipeline with `VolumeSlices`).
    #[serde(default)]
    pub volumes: Vec<volumes::VolumeDesc>,
    /// GPU memory budget in MiB: levels above the pinned coarse ones are paged in by
    /// demand (`--gpu-budget` overrides it).
    #[serde(default)]
    pub gpu_budget_mib: Option<u64>,
}

/// A pinhole camera as written in a scene.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position.
    pub position: (f64, f64, f64),
    /// Target point.
    #[serde(default)]
    pub look_at: (f64, f64, f64),
    /// Up direction.
    #[serde(default = "up")]
    pub up: (f64, f64, f64),
    /// Vertical field of view in degrees.
    #[serde(default = "fov")]
    pub fov_y: f64,
    /// Near plane.
    #[serde(default = "near")]
    pub near: f64,
    /// Far plane (0, the default: none, an infinite reversed-Z projection).
    #[serde(default)]
    pub far: f64,
}

fn up() -> (f64, f64, f64) {
    (0.0, 1.0, 0.0)
}
fn fov() -> f64 {
    45.0
}
fn near() -> f64 {
    0.01
}

impl Default for CameraDesc {
    fn default() -> Self {
        Self {
            position: (0.0, 0.0, 3.0),
            look_at: (0.0, 0.0, 0.0),
            up: up(),
            fov_y: fov(),
            near: near(),
            far: 0.0,
        }
    }
}

impl CameraDesc {
    /// The camera.
    pub fn camera(&self) -> Camera {
        let v = |t: (f64, f64, f64)| DVec3::new(t.0, t.1, t.2);
        Camera {
            position: v(self.position),
            look_at: v(self.look_at),
            up: v(self.up),
            fov_y_deg: self.fov_y,
            near: self.near,
            far: if self.far > 0.0 {
                self.far
            } else {
                f64::INFINITY
            },
        }
    }
}

/// LOD choice as written.
#[derive(Debug, Deserialize, Clone, Copy)]
pub enum LodDesc {
    /// A fixed level.
    Fixed(u32),
    /// Per instance, the coarsest level whose voxel projects to at most `pixel_error`
    /// pixels (default 1; 0 = finest), plus `bias` levels.
    Auto {
        /// Levels added (positive = finer).
        #[serde(default)]
        bias: i32,
        /// Largest projected voxel size in pixels.
        #[serde(default = "one")]
        pixel_error: f64,
    },
}

/// One voxel object.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// Model file (relative to the scene file).
    pub model: String,
    /// Voxelization level (finest LOD).
    pub level: u32,
    /// LOD policy (default: the finest level).
    #[serde(default)]
    pub lod: Option<LodDesc>,
    /// Placements (default: one at the origin).
    #[serde(default)]
    pub instances: Option<Vec<InstanceDesc>>,
    /// A mesh animation (`Twist(degrees_per_second: 90)`): the mesh is deformed and
    /// re-voxelized on the GPU for the time rendered (`ssbvb render --time T`).
    #[serde(default)]
    pub animate: Option<ssbvb_voxel::animate::MeshAnimation>,
    /// Brush edits applied to the finest level in order (`AddSphere`, `RemoveSphere`,
    /// `AddBox`, `RemoveBox`, in object space [-1, 1]³); the coarser levels follow.
    #[serde(default)]
    pub edits: Option<Vec<ssbvb_voxel::edit::Edit>>,
}

/// Most instances a scene file may hold (all objects together).
pub const MAX_INSTANCES: usize = 1 << 18;

/// Bad instances named one by one in an error; the rest are counted.
const MAX_LISTED: usize = 8;

/// A triangle object.
#[derive(Debug, Deserialize)]
pub enum TriangleDesc {
    /// A horizontal square facing +Y.
    Plane {
        /// Centre.
        center: (f64, f64, f64),
        /// Half the edge length.
        half_size: f32,
        /// Linear RGBA.
        color: (f32, f32, f32, f32),
    },
}

fn finite3(v: (f64, f64, f64)) -> bool {
    v.0.is_finite() && v.1.is_finite() && v.2.is_finite()
}

impl SceneFile {
    /// Values the renderer cannot use, each naming its field (empty when the file is
    /// usable). Checked before any model is voxelized.
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        let c = &self.camera;
        if !finite3(c.position) || !finite3(c.look_at) || !finite3(c.up) {
            out.push("camera: position, look_at and up must be finite".to_string());
        } else if c.position == c.look_at {
            out.push("camera: position and look_at are the same point".to_string());
        }
        if !(c.fov_y > 0.0 && c.fov_y < 180.0) {
            out.push(format!(
                "camera.fov_y must be in (0, 180) degrees, got {}",
                c.fov_y
            ));
        }
        if !(c.near > 0.0 && c.near.is_finite()) {
            out.push(format!(
                "camera.near must be a positive number, got {}",
                c.near
            ));
        } else if c.far > 0.0 && c.far <= c.near {
            out.push(format!(
                "camera.far ({}) must be beyond camera.near ({}), or 0 for no far plane",
                c.far, c.near
            ));
        }
        let total: usize = self
            .objects
            .iter()
            .map(|o| o.instances.as_ref().map_or(1, Vec::len))
            .sum();
        if total > MAX_INSTANCES {
            out.push(format!(
                "objects: {total} instances in all; a scene holds at most {MAX_INSTANCES} \
                 (each visible one costs a 160-byte GPU record and a hierarchy node)"
            ));
        }
        let mut bad_instances = 0;
        for (i, o) in self.objects.iter().enumerate() {
            if let Some(p) = o.animate.as_ref().and_then(|a| a.problem()) {
                out.push(format!("objects[{i}].animate: {p}"));
            }
            for (j, e) in o.edits.iter().flatten().enumerate() {
                if let Some(p) = e.problem() {
                    out.push(format!("objects[{i}].edits[{j}]: {p}"));
                }
            }
            if o.animate.is_some() && o.edits.as_ref().is_some_and(|e| !e.is_empty()) {
                out.push(format!(
                    "objects[{i}]: edits and animate together are not supported yet"
                ));
            }
            match o.lod {
                Some(LodDesc::Fixed(l)) if l > o.level => out.push(format!(
                    "objects[{i}].lod: Fixed({l}) is finer than the object's level {}",
                    o.level
                )),
                Some(LodDesc::Auto { pixel_error, .. })
                    if !(pixel_error >= 0.0 && pixel_error.is_finite()) =>
                {
                    out.push(format!(
                        "objects[{i}].lod: Auto pixel_error must be a finite number >= 0, got \
                         {pixel_error}"
                    ))
                }
                _ => {}
            }
            for (j, t) in o.instances.iter().flatten().enumerate() {
                let before = out.len();
                if !(t.scale > 0.0 && t.scale.is_finite()) {
                    out.push(format!(
                        "objects[{i}].instances[{j}].scale must be a positive number, got {}",
                        t.scale
                    ));
                }
                if !finite3(t.translation) || !t.rotation_y_deg.is_finite() {
                    out.push(format!(
                        "objects[{i}].instances[{j}]: translation and rotation_y_deg must be \
                         finite"
                    ));
                }
                // Name the first few bad instances, count the rest.
                if out.len() > before {
                    bad_instances += 1;
                    if bad_instances > MAX_LISTED {
                        out.truncate(before);
                    }
                }
            }
        }
        if bad_instances > MAX_LISTED {
            out.push(format!(
                "and {} more bad instances",
                bad_instances - MAX_LISTED
            ));
        }
        if let Some(b) = self.gpu_budget_mib {
            if b == 0 || b > MAX_GPU_BUDGET_MIB {
                out.push(format!(
                    "gpu_budget_mib must be 1..={} MiB, got {b}",
                    MAX_GPU_BUDGET_MIB
                ));
            }
        }
        for (i, v) in self.volumes.iter().enumerate() {
            out.extend(v.problems(i));
        }
        for (i, t) in self.triangles.iter().enumerate() {
            let TriangleDesc::Plane {
                center, half_size, ..
            } = t;
            if !(*half_size > 0.0 && half_size.is_finite() && finite3(*center)) {
                out.push(format!(
                    "triangles[{i}]: half_size must be a positive number and center finite"
                ));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn syntax_errors_name_the_line_and_bad_values_their_field() {
        let e = parse(
            "Scene(\n  camera: (position: (0.0, 0.0, 3.0),\n  oops: 1)",
            "s.ron",
        )
        .unwrap_err();
        assert!(matches!(e, SceneError::Syntax { line: 3, .. }), "{e}");
        assert!(e.to_string().starts_with("s.ron:3:"), "{e}");
        let e = parse(
            "Scene(camera: (position: (0.0, 0.0, 3.0), fov_y: 0.0))",
            "s.ron",
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "s.ron: camera.fov_y must be in (0, 180) degrees, got 0"
        );
        let ok = parse("Scene(gpu_budget_mib: 64)", "s.ron").unwrap();
        assert_eq!(ok.gpu_budget_mib, Some(64));
        assert!(ok.objects.is_empty());
        let e = parse("Scene(gpu_budget_mib: 0)", "s.ron").unwrap_err();
        assert!(
            e.to_string()
                .contains("gpu_budget_mib must be 1..=1048576 MiB, got 0"),
            "{e}"
        );
    }
}
