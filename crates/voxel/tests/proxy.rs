//! Proxy mesh tests on synthetic voxel sets: closed, outward, exact volume, encloses every
//! voxel, and every reference ray that hits a voxel crosses the proxy first.

use std::collections::HashSet;

use glam::DVec3;
use ssbvb_voxel::asset::{ProxyMesh, SparseLookup};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::proxy::{
    build_proxy, build_proxy_bricks, check_closed, proxy_encloses, signed_volume,
};
use ssbvb_voxel::reference::{Traversal, trace_object_ray};

#[path = "support/rng.rs"]
mod rng;

use rng::Rng;

/// Cells of a sphere shell: centre within `r` of the origin, some 6-neighbour outside.
fn shell_cells(level: u32, r: f64) -> Vec<[u32; 3]> {
    let n = 1i64 << level;
    let s = cell_size(level);
    let inside = |c: [i64; 3]| {
        let p =
            DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * s + DVec3::splat(-1.0 + 0.5 * s);
        p.length() <= r
    };
    let mut cells = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let c = [x, y, z];
                if inside(c)
                    && [
                        [1, 0, 0],
                        [-1, 0, 0],
                        [0, 1, 0],
                        [0, -1, 0],
                        [0, 0, 1],
                        [0, 0, -1],
                    ]
                    .iter()
                    .any(|d| !inside([x + d[0], y + d[1], z + d[2]]))
                {
                    cells.push([x as u32, y as u32, z as u32]);
                }
            }
        }
    }
    cells
}

/// Named synthetic voxel sets at `level`.
fn synthetic_sets(level: u32, rng: &mut Rng) -> Vec<(String, Vec<[u32; 3]>)> {
    let n = 1u32 << level;
    let mut sets = vec![
        ("single".to_string(), vec![[n / 3, n / 2, n - 1 - n / 5]]),
        (
            "corners".to_string(),
            vec![[0, 0, 0], [n - 1, n - 1, n - 1], [n - 1, 0, 0]],
        ),
        (
            "diagonal".to_string(),
            (0..n).map(|i| [i, i, n - 1 - i]).collect(),
        ),
    ];
    let random: HashSet<[u32; 3]> = (0..200.min(n * n * n))
        .map(|_| {
            [
                rng.below(n as u64) as u32,
                rng.below(n as u64) as u32,
                rng.below(n as u64) as u32,
            ]
        })
        .collect();
    sets.push(("random".to_string(), random.into_iter().collect()));
    // Dense sets only where a debug build enumerates the grid quickly.
    if level <= 7 {
        let k = n * 2 / 3;
        sets.push((
            "plane".to_string(),
            (0..n * n).map(|i| [i % n, k, i / n]).collect(),
        ));
        sets.push(("shell".to_string(), shell_cells(level, 0.8)));
    }
    sets
}

/// Volume of the union of occupied bricks, computed from the cells directly.
fn union_volume(level: u32, cells: &[[u32; 3]], brick: u32) -> f64 {
    let brick = brick.min(1 << level);
    let bricks: HashSet<[u32; 3]> = cells.iter().map(|c| c.map(|v| v / brick)).collect();
    bricks.len() as f64 * (brick as f64 * cell_size(level)).powi(3)
}

fn check(
    level: u32,
    name: &str,
    cells: &[[u32; 3]],
    brick: u32,
    mesh: &ProxyMesh,
    lookup: &SparseLookup,
) {
    check_closed(mesh).unwrap_or_else(|e| panic!("level {level} {name} brick {brick}: {e}"));
    proxy_encloses(lookup, mesh)
        .unwrap_or_else(|e| panic!("level {level} {name} brick {brick}: {e}"));
    let want = union_volume(level, cells, brick);
    let got = signed_volume(mesh);
    assert!(
        (got - want).abs() <= 1e-9 * want.max(1e-12),
        "level {level} {name}: volume {got} vs {want}"
    );
    for p in &mesh.positions {
        assert!(
            p.iter().all(|c| c.is_finite() && (-1.0..=1.0).contains(c)),
            "{p:?}"
        );
    }
}

#[test]
fn page_proxies_are_closed_outward_exact_and_enclosing_at_levels_0_to_10() {
    let mut rng = Rng(7);
    for level in 0..=10 {
        for (name, cells) in synthetic_sets(level, &mut rng) {
            let lookup = SparseLookup::from_cells(level, cells.iter().copied());
            let mesh = build_proxy(&lookup);
            check(level, &name, &cells, 16, &mesh, &lookup);
            if name == "single" {
                assert_eq!(mesh.triangles.len(), 12, "level {level}: one page is a box");
            }
        }
    }
}

#[test]
fn brick_proxies_are_tighter_and_still_enclosing() {
    let mut rng = Rng(11);
    for level in [3, 5, 6] {
        for (name, cells) in synthetic_sets(level, &mut rng) {
            let lookup = SparseLookup::from_cells(level, cells.iter().copied());
            let mut last_volume = f64::INFINITY;
            for brick in [16, 8, 4, 2, 1] {
                let mesh = build_proxy_bricks(&lookup, brick);
                check(level, &name, &cells, brick, &mesh, &lookup);
                let v = signed_volume(&mesh);
                assert!(
                    v <= last_volume + 1e-12,
                    "{name} brick {brick}: volume grew"
                );
                last_volume = v;
                if name == "shell" {
                    eprintln!(
                        "level {level} shell ({} voxels): brick {brick:2} -> {} triangles, volume {v:.4}",
                        cells.len(),
                        mesh.triangles.len()
                    );
                }
            }
        }
    }
}

/// First intersection of a ray with the mesh (edges inclusive), Möller–Trumbore in f64.
fn first_crossing(mesh: &ProxyMesh, o: DVec3, d: DVec3) -> Option<f64> {
    let mut best: Option<f64> = None;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)));
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            continue;
        }
        let inv = 1.0 / det;
        let s = o - a;
        let u = s.dot(p) * inv;
        let q = s.cross(e1);
        let v = d.dot(q) * inv;
        let eps = 1e-12;
        if u < -eps || v < -eps || u + v > 1.0 + eps {
            continue;
        }
        let t = e2.dot(q) * inv;
        if t >= 0.0 && best.is_none_or(|b| t < b) {
            best = Some(t);
        }
    }
    best
}

#[test]
fn every_ray_that_hits_a_voxel_crosses_the_proxy_first() {
    let mut rng = Rng(3);
    let views = [
        DVec3::new(2.5, 1.5, 3.0),
        DVec3::new(-3.0, 0.0, 0.0),
        DVec3::new(0.1, -3.5, 0.2),
        DVec3::new(-1.7, 2.2, -2.4),
    ];
    for level in [2, 5, 6] {
        for (name, cells) in synthetic_sets(level, &mut rng) {
            let lookup = SparseLookup::from_cells(level, cells.iter().copied());
            for brick in [16, 2] {
                let mesh = build_proxy_bricks(&lookup, brick);
                let mut hits = 0;
                for eye in views {
                    let cam = Camera {
                        fov_y_deg: 50.0,
                        ..Camera::new(eye, DVec3::ZERO)
                    };
                    let (w, h) = (24, 24);
                    for py in 0..h {
                        for px in 0..w {
                            let (o, d) = cam.ray(px, py, w, h);
                            let Some(hit) =
                                trace_object_ray(&lookup, o, d, Traversal::Hierarchical)
                            else {
                                continue;
                            };
                            hits += 1;
                            let t = first_crossing(&mesh, o, d).unwrap_or_else(|| {
                                panic!("level {level} {name} brick {brick}: ray {o} {d} hits {hit:?} but misses the proxy")
                            });
                            assert!(
                                t <= hit.t + 1e-9,
                                "level {level} {name}: proxy at {t} behind the voxel at {}",
                                hit.t
                            );
                        }
                    }
                }
                assert!(
                    hits > 0 || cells.len() < 10,
                    "level {level} {name}: no hits at all"
                );
            }
        }
    }
}

/// The test models (`assets/models`): every model, prepared at level 6 (the bunny also at 7): each
/// level's proxy (as `prepare_asset` stored it) is closed and encloses every voxel, and
/// reference rays that hit a voxel cross it first.
#[test]
fn shared_models_proxies_enclose_every_voxel() {
    use ssbvb_voxel::load::load_model;
    use ssbvb_voxel::prepare::prepare_asset;
    use ssbvb_voxel::progress::NoProgress;

    let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/models"));
    assert!(dir.is_dir(), "test models missing at {}", dir.display());
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| {
            matches!(
                p.extension().and_then(|e| e.to_str()),
                Some("obj" | "ply" | "vox")
            )
        })
        .collect();
    names.sort();
    assert!(
        names.len() >= 5,
        "expected the test models, found {names:?}"
    );
    for path in names {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let model = load_model(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let levels: &[u32] = if name.contains("bunny") {
            &[6, 7]
        } else {
            &[6]
        };
        for &level in levels {
            let (asset, _) =
                prepare_asset(&model, level, &NoProgress).unwrap_or_else(|e| panic!("{name}: {e}"));
            for lod in &asset.lods {
                let what = format!("{name} level {level} lod {}", lod.level);
                assert!(!lod.point_cloud.voxels.is_empty(), "{what}: no voxels");
                // The stored proxy against independent facts, not against the function
                // that built it: closed, enclosing every voxel, and exactly the volume of
                // the 16^3 pages the voxels occupy (counted from the voxels' cells).
                let cells: Vec<[u32; 3]> =
                    lod.point_cloud.voxels.iter().map(|v| v.cell()).collect();
                check(lod.level, &what, &cells, 16, &lod.proxy, &lod.lookup);
            }
            let finest = asset.lods.last().unwrap();
            eprintln!(
                "{name} level {level}: {} voxels, {} pages, proxy {} triangles",
                finest.point_cloud.voxels.len(),
                finest.lookup.occupied_pages(),
                finest.proxy.triangles.len()
            );
            // Rays through the model from two sides cross the proxy before any voxel.
            for eye in [DVec3::new(2.0, 1.2, 2.6), DVec3::new(-2.4, -0.6, -2.2)] {
                let cam = Camera {
                    fov_y_deg: 45.0,
                    ..Camera::new(eye, DVec3::ZERO)
                };
                for py in 0..20 {
                    for px in 0..20 {
                        let (o, d) = cam.ray(px, py, 20, 20);
                        if let Some(hit) =
                            trace_object_ray(&finest.lookup, o, d, Traversal::Hierarchical)
                        {
                            let t =
                                first_crossing(&finest.proxy, o, d).expect("ray misses the proxy");
                            assert!(t <= hit.t + 1e-9, "{name}: proxy behind the voxel");
                        }
                    }
                }
            }
        }
    }
}
