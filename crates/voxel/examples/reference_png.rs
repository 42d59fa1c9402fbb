//! Renders a synthetic scene (a voxel ball on a voxel floor) with the CPU reference ray
//! caster and writes the shaded image, the face normals and the depth as PNGs.
//!
//! ```text
//! cargo run --release -p ssbvb-voxel --example reference_png -- [OUT_DIR] [LEVEL] [SIZE] [MODEL]
//! ```
//!
//! Defaults: `out/reference_png`, level 9, 512 × 512. Prints the render time (the
//! reference caster's speed at that level) and the proxy triangle counts. With a model
//! file (OBJ, PLY, glTF, `.vox`) it also prepares that model at LEVEL and renders it to
//! `model.png`.

use std::time::Instant;

use glam::{DAffine3, DVec3};
use ssbvb_voxel::asset::{LodLevel, PackedVoxel, PointCloud, SparseLookup};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::proxy::{build_proxy, build_proxy_bricks};
use ssbvb_voxel::reference::{Instance, render};
use ssbvb_voxel::shading::Light;

/// A LOD level from packed voxels (sorted into Morton order: voxel id = Morton rank), with
/// its page proxy.
fn lod(level: u32, mut voxels: Vec<PackedVoxel>) -> LodLevel {
    voxels.sort_by_key(|v| ssbvb_voxel::svo::morton_encode(v.cell()));
    let lookup = SparseLookup::from_cells(level, voxels.iter().map(|v| v.cell()));
    let proxy = build_proxy(&lookup);
    LodLevel {
        level,
        point_cloud: PointCloud { voxels },
        lookup,
        proxy,
    }
}

/// The surface shell of a ball of radius `r` (cells whose centre is inside, with a
/// 6-neighbour outside), normals radial, colour varying with the normal.
fn ball(level: u32, r: f64) -> LodLevel {
    let n = 1i64 << level;
    let s = cell_size(level);
    let centre = |c: i64| -1.0 + (c as f64 + 0.5) * s;
    let inside = |x: i64, y: i64, z: i64| {
        let p = DVec3::new(centre(x), centre(y), centre(z));
        p.length_squared() <= r * r
    };
    let mut voxels = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                if !inside(x, y, z) {
                    continue;
                }
                let boundary = !inside(x + 1, y, z)
                    || !inside(x - 1, y, z)
                    || !inside(x, y + 1, z)
                    || !inside(x, y - 1, z)
                    || !inside(x, y, z + 1)
                    || !inside(x, y, z - 1);
                if boundary {
                    let nrm = DVec3::new(centre(x), centre(y), centre(z)).normalize();
                    let color = [
                        0.55 + 0.4 * nrm.x as f32,
                        0.35 + 0.3 * nrm.y as f32,
                        0.25 + 0.2 * nrm.z as f32,
                        1.0,
                    ];
                    let cell = [x as u32, y as u32, z as u32];
                    voxels.push(PackedVoxel::new(
                        cell,
                        nrm.as_vec3().to_array(),
                        color,
                        [0.0; 2],
                    ));
                }
            }
        }
    }
    lod(level, voxels)
}

/// A one-voxel-thick floor (the bottom layer of the grid), normals +Y, checkerboard.
fn floor(level: u32) -> LodLevel {
    let n = 1u32 << level;
    let voxels = (0..n * n)
        .map(|i| {
            let (x, z) = (i % n, i / n);
            let light = (x / 4 + z / 4) % 2 == 0;
            let c = if light {
                [0.75, 0.75, 0.7, 1.0]
            } else {
                [0.2, 0.3, 0.45, 1.0]
            };
            PackedVoxel::new([x, 0, z], [0.0, 1.0, 0.0], c, [0.0; 2])
        })
        .collect();
    lod(level, voxels)
}

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let out = std::path::PathBuf::from(args.next().unwrap_or_else(|| "out/reference_png".into()));
    let level: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(9);
    let size: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(512);
    std::fs::create_dir_all(&out)?;

    let t = Instant::now();
    let ball = ball(level, 0.9);
    let floor = floor(6);
    println!(
        "built ball (level {level}, {} voxels, {} pages) and floor in {:.2?}",
        ball.point_cloud.voxels.len(),
        ball.lookup.occupied_pages(),
        t.elapsed()
    );
    for brick in [16, 8, 4] {
        let t = Instant::now();
        let m = build_proxy_bricks(&ball.lookup, brick);
        println!(
            "ball proxy, brick {brick:2}: {} triangles, {} vertices ({:.2?})",
            m.triangles.len(),
            m.positions.len(),
            t.elapsed()
        );
    }

    let instances = [
        // The ball, radius 0.9 object units, standing on the floor.
        Instance {
            lod: &ball,
            object_to_world: DAffine3::from_translation(DVec3::new(0.0, 0.9, 0.0)),
            faces: None,
        },
        // The floor: 6 × 6 world units, its top face at y = 0.
        Instance {
            lod: &floor,
            object_to_world: DAffine3::from_scale(DVec3::splat(3.0))
                * DAffine3::from_translation(DVec3::new(0.0, 1.0 - cell_size(6), 0.0)),
            faces: None,
        },
    ];
    let camera = Camera {
        fov_y_deg: 40.0,
        ..Camera::new(DVec3::new(3.2, 2.6, 4.2), DVec3::new(0.0, 0.7, 0.0))
    };
    let light = Light::default();

    // One warm-up render (thread pool start-up, page faults), then the timed one.
    let _ = render(&instances, &camera, 64, 64, &light);
    let t = Instant::now();
    let img = render(&instances, &camera, size, size, &light);
    let elapsed = t.elapsed();
    println!(
        "rendered {size}x{size} in {elapsed:.2?} on {} threads: {} pixels covered, all finite: {}",
        rayon::current_num_threads(),
        img.coverage(),
        img.all_finite()
    );
    img.to_png(out.join("reference.png"))?;
    img.normals_to_png(out.join("reference_normals.png"))?;
    img.depth_to_png(out.join("reference_depth.png"))?;

    // The brief's benchmark: the ball alone, filling the view.
    let solo = [Instance {
        lod: &ball,
        object_to_world: DAffine3::IDENTITY,
        faces: None,
    }];
    let cam = Camera {
        fov_y_deg: 40.0,
        ..Camera::new(DVec3::new(0.3, 0.5, 3.0), DVec3::ZERO)
    };
    let t = Instant::now();
    let img = render(&solo, &cam, size, size, &light);
    println!(
        "ball alone: {size}x{size} in {:.2?}, {} pixels covered",
        t.elapsed(),
        img.coverage()
    );

    if let Some(model_path) = args.next() {
        let t = Instant::now();
        let model =
            ssbvb_voxel::load::load_model(model_path.as_ref()).map_err(std::io::Error::other)?;
        let (asset, _) =
            ssbvb_voxel::prepare::prepare_asset(&model, level, &ssbvb_voxel::progress::NoProgress)
                .map_err(std::io::Error::other)?;
        let finest = asset.lods.last().expect("a prepared asset has levels");
        println!(
            "prepared {model_path} at level {level} in {:.2?}: {} voxels, proxy {} triangles",
            t.elapsed(),
            finest.point_cloud.voxels.len(),
            finest.proxy.triangles.len()
        );
        let inst = [Instance {
            lod: finest,
            object_to_world: DAffine3::IDENTITY,
            faces: None,
        }];
        let cam = Camera {
            fov_y_deg: 40.0,
            ..Camera::new(DVec3::new(0.5, 0.6, 3.9), DVec3::ZERO)
        };
        // Warm up once, then time (the first render pays for page faults).
        let _ = render(&inst, &cam, size, size, &light);
        let t = Instant::now();
        let img = render(&inst, &cam, size, size, &light);
        println!(
            "model: {size}x{size} in {:.2?}, {} pixels covered",
            t.elapsed(),
            img.coverage()
        );
        img.to_png(out.join("model.png"))?;
        img.normals_to_png(out.join("model_normals.png"))?;
    }
    println!("wrote {}", out.display());
    Ok(())
}
