//! The lattice scenes and cameras of the tie tests: assets whose colour names each voxel,
//! seeded random grids, built corner cases, and views whose lattice pixels are known.

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_voxel::asset::{PackedVoxel, VoxelAsset};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::cell_size;

use super::{LEVEL, N, SMALL};

/// An asset at `LEVEL` holding `cells`, whose colour word names the object and the cell
/// (red: x + 16·object, green: y, blue: z), so a G-buffer's albedo tells which voxel of
/// which object a pixel shows.
pub(super) fn lattice_asset(cells: &[[u32; 3]], object: u32) -> Arc<VoxelAsset> {
    crate::empty_space::synthetic_asset_with(LEVEL, cells, |c, _| {
        let mut v = PackedVoxel::new(c, [0.0, 0.0, 1.0], [0.0; 4], [0.0; 2]);
        v.color = color_word(object, c);
        v
    })
}

pub(super) fn color_word(object: u32, c: [u32; 3]) -> u32 {
    (c[0] + 16 * object) | (c[1] << 8) | (c[2] << 16) | (0xff << 24)
}

/// The cells of a `LEVEL` grid kept by a seeded hash at `density`.
pub(super) fn random_cells(seed: u64, density: f64) -> Vec<[u32; 3]> {
    let n = 1u32 << LEVEL;
    let mut out = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let mut h = seed ^ ((x as u64) << 32 | (y as u64) << 16 | z as u64);
                // splitmix64
                h = h.wrapping_add(0x9e37_79b9_7f4a_7c15);
                h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
                h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
                h ^= h >> 31;
                if (h >> 11) as f64 / (1u64 << 53) as f64 <= density {
                    out.push([x, y, z]);
                }
            }
        }
    }
    out
}

pub(super) fn scene_of(objects: Vec<(Arc<VoxelAsset>, DAffine3)>) -> Scene {
    Scene {
        objects: objects
            .into_iter()
            .map(|(asset, xf)| VoxelObject {
                asset,
                instances: vec![xf],
                lod: LodPolicy::Fixed(LEVEL),
            })
            .collect(),
        ..Default::default()
    }
}

/// The pixels of a view whose rays are lattice rays.
#[derive(Clone, Copy, Debug)]
pub(super) enum Lattice {
    /// Axis-aligned camera: the pixels `(i, i)`, the centre row and the centre column.
    Axis,
    /// Space-diagonal camera: the centre pixel.
    Centre,
}

/// The lattice pixels of an `n × n` view (`n` odd).
pub(super) fn lattice_pixels(l: Lattice, n: u32) -> Vec<(u32, u32)> {
    let mid = n / 2;
    match l {
        Lattice::Centre => vec![(mid, mid)],
        Lattice::Axis => {
            let mut v: Vec<(u32, u32)> = (0..n).map(|i| (i, i)).collect();
            v.extend((0..n).filter(|&i| i != mid).map(|i| (i, mid)));
            v.extend((0..n).filter(|&i| i != mid).map(|i| (mid, i)));
            v
        }
    }
}

/// A named camera over a scene, and which of its pixels are lattice rays.
pub(super) struct View {
    pub(super) name: String,
    pub(super) camera: Camera,
    pub(super) lattice: Lattice,
    /// Width and height in pixels (odd).
    pub(super) size: u32,
}

pub(super) fn view(name: &str, position: [f64; 3], look_at: [f64; 3], lattice: Lattice) -> View {
    View {
        name: name.to_string(),
        camera: Camera::new(DVec3::from(position), DVec3::from(look_at)),
        lattice,
        size: N,
    }
}

pub(super) fn random_scene() -> Scene {
    scene_of(vec![(
        lattice_asset(&random_cells(7, 0.12), 0),
        DAffine3::IDENTITY,
    )])
}

/// Denser, for the many-camera views: most corners and edges have occupied cells around.
pub(super) fn dense_random_scene() -> Scene {
    scene_of(vec![(
        lattice_asset(&random_cells(13, 0.35), 0),
        DAffine3::IDENTITY,
    )])
}

pub(super) fn axis_views() -> Vec<View> {
    let mut far = view(
        "far (object_ray)",
        [0.0, 0.0, 100.0],
        [0.0; 3],
        Lattice::Axis,
    );
    far.camera.fov_y_deg = 1.3;
    // A lens wider than the grid: the outer rays pass beside the box.
    let mut wide = view("along -z, wide", [0.0, 0.0, 3.0], [0.0; 3], Lattice::Axis);
    wide.camera.fov_y_deg = 100.0;
    vec![
        view("along -z", [0.0, 0.0, 3.0], [0.0; 3], Lattice::Axis),
        view(
            "along -z, off centre",
            [0.25, -0.125, 3.0],
            [0.25, -0.125, 0.0],
            Lattice::Axis,
        ),
        view("along -x", [3.0, 0.0, 0.0], [0.0; 3], Lattice::Axis),
        // Faces entered from below (negative geometric normals: the octahedral
        // encoding's folded half).
        view("along +z", [0.0, 0.0, -3.0], [0.0; 3], Lattice::Axis),
        view(
            "space diagonal from below",
            [-3.0, -3.0, -3.0],
            [0.0; 3],
            Lattice::Centre,
        ),
        far,
        view("space diagonal", [3.0, 3.0, 3.0], [0.0; 3], Lattice::Centre),
        view(
            "space diagonal, off",
            [3.125, 2.75, 3.0],
            [0.125, -0.25, 0.0],
            Lattice::Centre,
        ),
        wide,
    ]
}

/// Small views of many lattice cameras: along -z from cell lines, the first and last inner
/// planes among them (the centre ray runs along a cell edge: in two cell planes at once),
/// and along the space diagonal from lattice points (the centre ray passes through cell
/// corners).
pub(super) fn many_camera_views() -> Vec<View> {
    let s = cell_size(LEVEL);
    let mut views = Vec::new();
    for i in [-7.0, -3.0, 0.0, 3.0, 7.0] {
        for j in [-6.0, -2.0, 1.0, 5.0] {
            let (x, y) = (i * s, j * s);
            let mut v = view("edge line", [x, y, 3.0], [x, y, 0.0], Lattice::Axis);
            v.size = SMALL;
            views.push(v);
        }
    }
    for i in [-4.0, 0.0, 3.0] {
        for j in [-5.0, 0.0, 2.0] {
            for k in [-3.0, 0.0, 4.0] {
                let p = DVec3::new(3.0 + i * s, 3.0 + j * s, 3.0 + k * s);
                let mut v = view("corner", p.into(), (p - 3.0).into(), Lattice::Centre);
                v.size = SMALL;
                views.push(v);
            }
        }
    }
    views
}

/// Scenes built around the grid's centre corner, seen along the space diagonal from
/// outside (the ray reaches the corner after empty cells) and from the corner itself (a
/// camera on three cell planes: the cells behind it are touched at t = 0), with only two
/// of the seven cells touched there occupied: the two the rank order must choose between
/// (one differing from the cell entered diagonally on x or y against one differing on z;
/// on x against on y).
pub(super) fn corner_choice_scenes() -> Vec<(Scene, Vec<View>)> {
    [[[8, 8, 7], [7, 7, 8]], [[7, 8, 7], [8, 7, 7]]]
        .into_iter()
        .map(|cells| {
            let scene = scene_of(vec![(lattice_asset(&cells, 0), DAffine3::IDENTITY)]);
            let mut views = vec![
                view("corner from outside", [3.0; 3], [0.0; 3], Lattice::Centre),
                view(
                    "corner from the corner",
                    [0.0; 3],
                    [-1.0; 3],
                    Lattice::Centre,
                ),
            ];
            for v in &mut views {
                v.size = SMALL;
            }
            (scene, views)
        })
        .collect()
}

/// Two objects at the same transform (same cells, told apart by colour): every hit is an
/// exact tie between instances, which goes to the lower index.
pub(super) fn duplicates_scene() -> Scene {
    let cells = random_cells(11, 0.12);
    scene_of(vec![
        (lattice_asset(&cells, 0), DAffine3::IDENTITY),
        (lattice_asset(&cells, 1), DAffine3::IDENTITY),
    ])
}

/// Views of the duplicates: two along axes, and a near camera half a unit from the grid's
/// face.
pub(super) fn duplicates_views() -> Vec<View> {
    let mut views: Vec<View> = axis_views().into_iter().take(2).collect();
    views.push(view(
        "near, along -z",
        [0.0, 0.0, 1.5],
        [0.0; 3],
        Lattice::Axis,
    ));
    views
}

/// A small solid block inside a sparse object's box, just behind its front: the prepass
/// names the sparse object (its proxy is nearer), and the block, hit first wherever the
/// sparse object's voxels lie deeper, is found by the instance walk, within one unit of
/// the camera of [`nested_view`].
pub(super) fn nested_scene() -> Scene {
    let n = 1u32 << LEVEL;
    let block: Vec<[u32; 3]> = (0..n)
        .flat_map(|z| (0..n).flat_map(move |y| (0..n).map(move |x| [x, y, z])))
        .collect();
    scene_of(vec![
        (lattice_asset(&random_cells(7, 0.12), 0), DAffine3::IDENTITY),
        (
            lattice_asset(&block, 1),
            DAffine3::from_scale_rotation_translation(
                DVec3::splat(0.25),
                glam::DQuat::IDENTITY,
                DVec3::new(0.0, 0.0, 0.5),
            ),
        ),
    ])
}

/// Along -z, half a unit from the sparse object's front face.
pub(super) fn nested_view() -> View {
    view("nested, near", [0.0, 0.0, 1.5], [0.0; 3], Lattice::Axis)
}

/// The random grid drawn at its coarsest level (one voxel, the whole box): the casters'
/// level-0 paths.
pub(super) fn level_zero_scene() -> Scene {
    let mut scene = random_scene();
    scene.objects[0].lod = LodPolicy::Fixed(0);
    scene
}

/// An object with no voxels first, overlapping the random grid, a quarter unit nearer the
/// views along -z: it draws nothing (its octree has no root, its lookup no node).
pub(super) fn empty_first_scene() -> Scene {
    scene_of(vec![
        (
            lattice_asset(&[], 0),
            DAffine3::from_translation(DVec3::new(0.0, 0.0, 0.25)),
        ),
        (lattice_asset(&random_cells(7, 0.12), 1), DAffine3::IDENTITY),
    ])
}

/// Two objects touching at the world plane x = 0, seen along it: the centre column's rays
/// run inside that plane and touch both.
pub(super) fn touching_scene() -> Scene {
    scene_of(vec![
        (
            lattice_asset(&random_cells(3, 0.2), 0),
            DAffine3::from_translation(DVec3::new(-1.0, 0.0, 0.0)),
        ),
        (
            lattice_asset(&random_cells(5, 0.2), 1),
            DAffine3::from_translation(DVec3::new(1.0, 0.0, 0.0)),
        ),
    ])
}

/// The float just below (more negative than) the cell plane x = -0.125 of a `LEVEL` grid.
const BELOW_PLANE: f64 = -(0.125 + 1.0 / (1u64 << 26) as f64);

/// A solid block around the grid's centre; a camera on the grid's face, cameras inside a voxel (at a cell centre and on
/// a grid corner) with a wide lens, so that some pixels' rays have two equal dominant
/// components.
pub(super) fn inside_scene_and_views() -> (Scene, Vec<View>) {
    let mut cells = Vec::new();
    for z in 5..11 {
        for y in 5..11 {
            for x in 5..11 {
                cells.push([x, y, z]);
            }
        }
    }
    // A patch of the top layer, for a camera on the grid's top face, and one of the -x
    // face, for a camera inside a voxel there.
    for y in 7..10 {
        for x in 7..10 {
            cells.push([x, y, 15]);
            cells.push([0, x, y]);
        }
    }
    let scene = scene_of(vec![(lattice_asset(&cells, 0), DAffine3::IDENTITY)]);
    let s = cell_size(LEVEL);
    let c = -1.0 + 8.5 * s;
    let mut views = vec![
        // On the grid's top face above an occupied cell: its plane is crossed at t = 0,
        // so the face is the entered one, not the inside rule's dominant axis.
        view("on the box face", [c, c, 1.0], [c, c, 0.0], Lattice::Axis),
        view(
            "inside, cell centre",
            [c, c, c],
            [c, c, -1.0],
            Lattice::Axis,
        ),
        view(
            "inside, grid corner",
            [0.0; 3],
            [0.0, 0.0, -1.0],
            Lattice::Axis,
        ),
        // Off the cell's centre: the dominant axis is not the axis of the nearest face.
        view(
            "inside, off centre",
            [c + 0.3 * s, c - 0.2 * s, c + 0.1 * s],
            [c + 0.3 * s, c - 0.2 * s, -1.0],
            Lattice::Axis,
        ),
        // Inside a voxel by the grid's -x face: where the ray moves toward +x, the face
        // behind the camera is the latest entry plane, not the dominant axis's.
        view(
            "inside, by the grid's face",
            [-1.0 + 0.5 * s, c, c],
            [-1.0 + 0.5 * s, c, -1.0],
            Lattice::Axis,
        ),
        // One float below the cell plane x = -0.125: `x + 1` rounds up onto the plane in
        // f32, so a start cell taken from `floor((x + 1) / s)` is one too high (cell 7,
        // not 6); the exact crossing times must settle it.
        view(
            "inside, one float below a cell plane",
            [BELOW_PLANE, c, c],
            [BELOW_PLANE, c, -1.0],
            Lattice::Axis,
        ),
        view(
            "inside, diagonal",
            [c, c, c],
            [c - 1.0, c - 1.0, c - 1.0],
            Lattice::Centre,
        ),
    ];
    for v in &mut views[..6] {
        v.camera.fov_y_deg = 120.0;
    }
    (scene, views)
}
