//! Scenes in the page: a bundled scene file's text and its models' bytes (fetched, not
//! read from disk) made into what the GPU draws by the engine's scene building
//! ([`ssbvb_engine::scene_file`], what `ssbvb render` uses too), with the models prepared
//! in the page's worker. A model dropped on the page becomes a scene of its own.
//!
//! What a scene file may hold that needs the file system or GPU-side preparation
//! (animated meshes, brush edits, translucent volumes, a GPU budget with pages streamed
//! from the cache) is refused with a message naming the field, not ignored.

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_engine::scene_file::{Prepared, SceneDescription};
use ssbvb_gpu::scene::{LodPolicy, Scene, TriangleObject, VoxelObject};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;

use crate::WebError;

/// The finest level a model dropped on the page may be voxelized at: level 10 of the bunny
/// is ~2.6 M voxels, ~100 MB of the wasm heap's 4 GiB while it is prepared.
pub const MAX_DROPPED_LEVEL: u32 = 10;

/// Largest model file the page takes (bytes): beyond it the browser tab's memory, not the
/// renderer, is the limit.
pub const MAX_MODEL_BYTES: usize = 256 << 20;

/// A scene file read and checked, its models not yet fetched.
#[derive(Debug)]
pub struct ParsedScene {
    /// Where it came from, for messages.
    pub name: String,
    description: SceneDescription,
}

/// Parses a scene file's text; `name` names it in errors.
pub fn parse_scene(text: &str, name: &str) -> Result<ParsedScene, WebError> {
    let description =
        SceneDescription::parse(text, name).map_err(|e| WebError::Scene(e.to_string()))?;
    let file = &description.file;
    let refuse = |field: String| {
        Err(WebError::Scene(format!(
            "{name}: {field} is not supported in the browser (use `ssbvb render`)"
        )))
    };
    if !file.volumes.is_empty() {
        return refuse("volumes".into());
    }
    if file.gpu_budget_mib.is_some() {
        return refuse("gpu_budget_mib".into());
    }
    for (i, o) in file.objects.iter().enumerate() {
        if o.animate.is_some() {
            return refuse(format!("objects[{i}].animate"));
        }
        if o.edits.as_ref().is_some_and(|e| !e.is_empty()) {
            return refuse(format!("objects[{i}].edits"));
        }
    }
    Ok(ParsedScene {
        name: name.to_string(),
        description,
    })
}

impl ParsedScene {
    /// Each object's model path (relative to the scene file) and level, in object order.
    pub fn models(&self) -> Vec<(String, u32)> {
        self.description.models()
    }

    /// The scene's camera.
    pub fn camera(&self) -> Camera {
        self.description.camera()
    }

    /// The scene with `assets[i]` as object `i`'s asset (prepared at its level).
    pub fn build(&self, assets: Vec<Arc<VoxelAsset>>) -> Result<Scene, WebError> {
        let source = Prepared {
            assets: self.models().into_iter().zip(assets).collect(),
        };
        self.description
            .build(&source, &ssbvb_voxel::progress::NoProgress)
            .map(|c| c.scene)
            .map_err(|e| WebError::Scene(e.to_string()))
    }
}

/// A model prepared from its bytes, with what its load could not do (each line naming the
/// file: a material or texture a model's bytes refer to is not fetched).
pub type PreparedModel = (VoxelAsset, Vec<String>);

/// Loads a model from its bytes (`name`'s extension, else its first bytes, say the format)
/// and prepares it at `level`: the asset `ssbvb voxelize` would write to its cache.
pub fn prepare_model(bytes: &[u8], name: &str, level: u32) -> Result<PreparedModel, WebError> {
    prepare_model_with(bytes, name, level, &ssbvb_voxel::progress::NoProgress)
}

/// [`prepare_model`] reporting its stages to `progress`.
pub fn prepare_model_with(
    bytes: &[u8],
    name: &str,
    level: u32,
    progress: &dyn ssbvb_voxel::progress::Progress,
) -> Result<PreparedModel, WebError> {
    let bad = |message: String| WebError::Model {
        name: name.to_string(),
        message,
    };
    if bytes.len() > MAX_MODEL_BYTES {
        return Err(bad(format!(
            "{} MiB is more than the page takes ({} MiB)",
            bytes.len() >> 20,
            MAX_MODEL_BYTES >> 20
        )));
    }
    let (asset, warnings) = ssbvb_engine::scene_file::prepare_bytes(bytes, name, level, progress)
        .map_err(|e| bad(e.to_string()))?;
    Ok((asset, warnings.iter().map(ToString::to_string).collect()))
}

/// A dropped model's scene: the model at the origin on a ground plane under its lowest
/// voxel, seen as the default scene sees the bunny.
pub fn model_scene(asset: Arc<VoxelAsset>) -> (Scene, Camera) {
    let level = asset.lods.len() as u32 - 1;
    let lowest = lowest_voxel_y(&asset);
    let mut scene = Scene::default();
    scene.objects.push(VoxelObject {
        asset,
        instances: vec![DAffine3::IDENTITY],
        lod: LodPolicy::Fixed(level),
    });
    scene.triangles.push(TriangleObject::ground_plane(
        DVec3::new(0.0, lowest - 0.01, 0.0),
        3.0,
        [0.45, 0.5, 0.45, 1.0],
    ));
    let camera = Camera {
        fov_y_deg: 40.0,
        near: 0.01,
        far: 100.0,
        ..Camera::new(DVec3::new(1.9, 0.9, 2.7), DVec3::new(0.0, -0.15, 0.0))
    };
    (scene, camera)
}

/// The object-space height of the bottom of the lowest voxel of the finest level.
fn lowest_voxel_y(asset: &VoxelAsset) -> f64 {
    let lod = asset.lods.last().expect("an asset has a level");
    let cells = f64::from(1u32 << (asset.lods.len() - 1));
    let min_y = lod
        .point_cloud
        .voxels
        .iter()
        .map(|v| v.cell()[1])
        .min()
        .unwrap_or(0);
    -1.0 + 2.0 * f64::from(min_y) / cells
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: &[u8] = b"v -1 -1 -1\nv 1 -1 0\nv 0 1 1\nf 1 2 3\n";

    #[test]
    fn what_the_page_cannot_draw_is_refused_by_field() {
        for (text, field) in [
            ("Scene(gpu_budget_mib: 64)", "gpu_budget_mib"),
            (
                "Scene(objects: [(model: \"a.obj\", level: 3), (model: \"a.obj\", level: 3, animate: Twist(degrees_per_second: 90.0))])",
                "objects[1].animate",
            ),
            (
                "Scene(objects: [(model: \"a.obj\", level: 3, edits: [RemoveSphere(center: (0.0, 0.0, 0.0), radius: 0.2)])])",
                "objects[0].edits",
            ),
            (
                "Scene(volumes: [(source: Cloud(seed: 1), edge: 16)])",
                "volumes",
            ),
        ] {
            let e = parse_scene(text, "s.ron").unwrap_err().to_string();
            assert!(
                e.contains(&format!("s.ron: {field} is not supported in the browser")),
                "{text}: {e}"
            );
        }
        let e = parse_scene("Scene(bogus: 1)", "s.ron")
            .unwrap_err()
            .to_string();
        assert!(e.contains("s.ron:1:"), "{e}");
    }

    #[test]
    fn a_scene_lists_its_models_and_builds_its_objects() {
        let s = parse_scene(
            "Scene(objects: [(model: \"../models/a.obj\", level: 3, lod: Fixed(2), \
             instances: [(translation: (1.0, 0.0, 0.0)), ()])], \
             triangles: [Plane(center: (0.0, -1.0, 0.0), half_size: 2.0, color: (1.0, 1.0, 1.0, 1.0))])",
            "s.ron",
        )
        .unwrap();
        assert_eq!(s.models(), vec![("../models/a.obj".to_string(), 3)]);
        let asset = Arc::new(prepare_model(TRI, "a.obj", 3).unwrap().0);
        assert_eq!(asset.lods.len(), 4);
        let scene = s.build(vec![asset]).unwrap();
        assert_eq!(scene.objects[0].lod, LodPolicy::Fixed(2));
        assert_eq!(scene.objects[0].instances.len(), 2);
        assert_eq!(
            scene.objects[0].instances[0].translation,
            DVec3::new(1.0, 0.0, 0.0)
        );
        assert_eq!(scene.triangles.len(), 1);
    }

    #[test]
    fn bad_models_name_the_file_and_why() {
        // A model whose MTL library is not among the bytes: a warning naming it.
        let (_, warnings) = prepare_model(
            b"mtllib m.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "a.obj",
            3,
        )
        .unwrap();
        assert!(warnings.iter().any(|w| w.contains("m.mtl")), "{warnings:?}");
        let e = prepare_model(b"ply\nformat nonsense\nend_header\n", "broken.ply", 4)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("broken.ply: "), "{e}");
        let e = prepare_model(b"\x00\x01garbage", "thing.bin", 4)
            .unwrap_err()
            .to_string();
        assert!(e.contains("thing.bin: not a model ssbvb reads"), "{e}");
        let e = prepare_model(TRI, "a.obj", 40).unwrap_err().to_string();
        assert!(e.starts_with("a.obj: "), "{e}");
        let e = prepare_model(&vec![b' '; MAX_MODEL_BYTES + 1], "big.obj", 4)
            .unwrap_err()
            .to_string();
        assert!(e.contains("more than the page takes"), "{e}");
    }

    /// A dropped model stands on its ground plane: the plane is just under its lowest
    /// voxel, and the camera is the default scene's.
    #[test]
    fn a_dropped_model_stands_on_its_ground() {
        let asset = Arc::new(prepare_model(TRI, "a.obj", 4).unwrap().0);
        let (scene, camera) = model_scene(asset);
        assert_eq!(scene.objects[0].lod, LodPolicy::Fixed(4));
        // The triangle's lowest corner is at y = -1: the lowest cell starts there.
        let t = &scene.triangles[0];
        let y = t
            .transform
            .transform_point3(DVec3::from(t.positions[0].map(f64::from)))
            .y;
        assert!((y - (-1.01)).abs() < 1e-6, "{y}");
        assert_eq!(camera.look_at, DVec3::new(0.0, -0.15, 0.0));
    }
}
