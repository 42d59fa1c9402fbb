//! The lighting reference ([`ssbvb_voxel::lighting`]) against closed forms, and the scene
//! volume on a placed cube: which cells are opaque, lit and shadowed.

use glam::{DAffine3, DVec3};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::lighting::monte_carlo::monte_carlo;
use ssbvb_voxel::lighting::volume::{RadianceVolume, VolumeInstance, mip_dims};
use ssbvb_voxel::lighting::{LightingParams, LightingSample};
use ssbvb_voxel::prepare::prepare_voxel_set;
use ssbvb_voxel::procedural::ProceduralModel;
use ssbvb_voxel::progress::NoProgress;
use ssbvb_voxel::reference::{Instance, Tracer};
use ssbvb_voxel::shading::Light;

/// A completely full 4³ grid: placed with a scale, any solid box.
fn full_cube() -> VoxelAsset {
    let set = ProceduralModel::Random {
        fraction: 1.0,
        seed: 0,
    }
    .voxels(2)
    .unwrap();
    prepare_voxel_set(set, &NoProgress).0
}

/// The object-space cube [-1, 1]³ placed as the box `lo..hi`.
fn boxed(lo: DVec3, hi: DVec3) -> DAffine3 {
    DAffine3::from_scale_rotation_translation(
        (hi - lo) * 0.5,
        glam::DQuat::IDENTITY,
        (hi + lo) * 0.5,
    )
}

/// The full cube's finest level placed by `m`, traced without face masks.
fn placed(asset: &VoxelAsset, m: DAffine3) -> Instance<'_> {
    Instance {
        lod: &asset.lods[2],
        object_to_world: m,
        faces: None,
    }
}

fn light_along(d: DVec3) -> Light {
    Light {
        direction: [d.x as f32, d.y as f32, d.z as f32],
        ..Light::default()
    }
}

fn lit_at(instances: &[Instance], light: &Light, p: DVec3, n: DVec3, max: f64) -> LightingSample {
    let params = LightingParams {
        max_distance: max,
        shadow_aperture: 10.0,
        near: 1e-6,
    };
    monte_carlo(&Tracer::new(instances), light, &params, p, n, 4096, 7)
}

#[test]
fn ao_facing_a_wall_is_the_squared_ratio_of_distance_to_radius() {
    // A wall filling z < 0 near the axis; the receiver at z = d faces it. A cosine-weighted
    // direction at angle θ meets it at d / cos θ, within D when cos θ ≥ d / D, which has
    // probability 1 − (d/D)²: AO = (d/D)².
    let asset = full_cube();
    let wall = boxed(DVec3::new(-50.0, -50.0, -1.0), DVec3::new(50.0, 50.0, 0.0));
    let inst = [placed(&asset, wall)];
    let light = light_along(DVec3::Z);
    for (d, max) in [(0.5, 1.0), (0.3, 1.0), (0.8, 1.0), (1.5, 1.0)] {
        let s = lit_at(&inst, &light, DVec3::new(0.0, 0.0, d), -DVec3::Z, max);
        let want: f64 = if d >= max { 1.0 } else { (d / max) * (d / max) };
        assert!(
            (f64::from(s.ao) - want).abs() < 0.01,
            "d {d}: {} vs {want}",
            s.ao
        );
        // Facing away: open.
        let away = lit_at(&inst, &light, DVec3::new(0.0, 0.0, d), DVec3::Z, max);
        assert_eq!(away.ao, 1.0);
        assert_eq!((away.shadow, away.indirect), (1.0, [0.0; 3]));
    }
}

#[test]
fn a_half_plane_over_the_receiver_shadows_half_the_light_cone() {
    // A slab over x < 0 at height 1..2; the light straight above: the cone's directions
    // with x < 0 meet it.
    let asset = full_cube();
    let slab = boxed(DVec3::new(-100.0, -100.0, 1.0), DVec3::new(0.0, 100.0, 2.0));
    let inst = [placed(&asset, slab)];
    let light = light_along(DVec3::Z);
    let s = lit_at(&inst, &light, DVec3::ZERO, DVec3::Z, 0.5);
    assert!((s.shadow - 0.5).abs() < 0.01, "{}", s.shadow);
    // Well under the slab: dark; well beside it: lit.
    assert_eq!(
        lit_at(&inst, &light, DVec3::new(-1.0, 0.0, 0.0), DVec3::Z, 0.5).shadow,
        0.0
    );
    assert_eq!(
        lit_at(&inst, &light, DVec3::new(1.0, 0.0, 0.0), DVec3::Z, 0.5).shadow,
        1.0
    );
    // The slab is out of AO reach at 0.5 and within it at 3.
    let near = lit_at(&inst, &light, DVec3::new(-1.0, 0.0, 0.0), DVec3::Z, 0.5);
    assert_eq!(near.ao, 1.0);
    let far = lit_at(&inst, &light, DVec3::new(-1.0, 0.0, 0.0), DVec3::Z, 3.0);
    assert!(far.ao < 0.5, "{}", far.ao);
}

#[test]
fn the_volume_marks_the_cube_opaque_lights_its_top_and_shadows_what_is_below() {
    let asset = full_cube();
    // Two cubes, one above the other with a gap; the light straight above.
    let upper = boxed(DVec3::new(-1.0, 2.0, -1.0), DVec3::new(1.0, 4.0, 1.0));
    let lower = boxed(DVec3::new(-1.0, -2.0, -1.0), DVec3::new(1.0, 0.0, 1.0));
    let instances = [upper, lower].map(|m| VolumeInstance {
        asset: &asset,
        object_to_world: m,
    });
    let light = light_along(DVec3::Y);
    let v = RadianceVolume::build(&instances, &light, 64);
    assert_eq!(v.dims.map(|d| d % 64), [0; 3]);
    assert_eq!(v.exact_levels(), v.mips.len());
    assert!(v.dims.iter().all(|&d| d <= 64));
    let at = |w: DVec3| {
        let c = ((w - v.origin) / v.cell).floor();
        let i =
            c.x as usize + v.dims[0] as usize * (c.y as usize + v.dims[1] as usize * c.z as usize);
        v.mips[0][i]
    };
    // Inside either cube: opaque; in the gap: empty.
    assert_eq!(at(DVec3::new(0.0, 3.0, 0.0))[3], 1.0);
    assert_eq!(at(DVec3::new(0.0, -1.0, 0.0))[3], 1.0);
    assert_eq!(at(DVec3::new(0.0, 1.0, 0.0)), [0.0; 4]);
    // The upper cube's top face is lit (its cells' normals point up), the lower cube's is
    // in the upper one's shadow.
    let top = at(DVec3::new(0.0, 4.0 - v.cell * 0.5, 0.0));
    assert!(top[1] > 0.1, "{top:?}");
    let shaded = at(DVec3::new(0.0, -v.cell * 0.5, 0.0));
    assert_eq!(shaded[3], 1.0);
    assert_eq!(&shaded[..3], &[0.0; 3], "{shaded:?}");
    // The mip chain runs down to one texel and keeps the mean opacity.
    assert_eq!(mip_dims(v.dims, v.mips.len() as u32 - 1), [1, 1, 1]);
    let mean =
        |k: usize| v.mips[k].iter().map(|t| f64::from(t[3])).sum::<f64>() / v.mips[k].len() as f64;
    assert!((mean(0) - mean(1)).abs() < 1e-4, "{} {}", mean(0), mean(1));
    assert!(v.occupied > 0 && v.bytes() > 8 * v.mips[0].len() as u64);
}

#[test]
fn a_volume_stays_within_its_cell_budget() {
    // A cubic scene at the largest resolution would be 512³ cells: lowered to fit 2^24.
    let asset = full_cube();
    let inst = [VolumeInstance {
        asset: &asset,
        object_to_world: DAffine3::IDENTITY,
    }];
    let v = RadianceVolume::build(&inst, &Light::default(), 512);
    let cells: u64 = v.dims.iter().map(|&d| u64::from(d)).product();
    assert!(
        cells <= ssbvb_voxel::lighting::volume::MAX_CELLS,
        "{:?}",
        v.dims
    );
    assert!(v.dims[0] >= 192, "lowered too far: {:?}", v.dims);
}

#[test]
fn the_bounce_from_a_lit_wall_is_its_radiance_times_the_blocked_fraction() {
    // The wall of the AO test with the light straight at its face (+Z): its face voxels'
    // stored normals point along +Z (the 4³ grid is symmetric about them), so each ray
    // that meets it within D brings albedo · light back: bounce = albedo · (1 - (d/D)²).
    // Lit from behind, the face sends nothing.
    let asset = full_cube();
    let wall = boxed(DVec3::new(-50.0, -50.0, -1.0), DVec3::new(50.0, 50.0, 0.0));
    let inst = [placed(&asset, wall)];
    let (d, max) = (0.5, 1.0);
    // Over the middle of one face voxel (each is 25 units wide; voxels differ in colour):
    // every ray within reach meets that voxel.
    let p = DVec3::new(12.5, 12.5, d);
    let front = lit_at(&inst, &light_along(DVec3::Z), p, -DVec3::Z, max);
    let tracer = Tracer::new(&inst);
    let hit = tracer.trace(p, -DVec3::Z).unwrap();
    let (albedo, normal) = tracer.surface(&hit);
    assert!((normal[2] - 1.0).abs() < 1e-3, "{normal:?}");
    let blocked = 1.0 - (d / max) * (d / max);
    for (got, a) in front.indirect.iter().zip(albedo) {
        let want = f64::from(a) * blocked;
        assert!(
            (f64::from(*got) - want).abs() < 0.01,
            "{:?} vs {want}",
            front.indirect
        );
    }
    assert!(front.indirect[0] > 0.1);
    let behind = lit_at(&inst, &light_along(-DVec3::Z), p, -DVec3::Z, max);
    assert_eq!(behind.indirect, [0.0; 3]);
    // Lit, but the light's cone is blocked by the wall for this receiver: no direct light.
    assert_eq!(behind.shadow, 0.0);
}

#[test]
fn each_receiver_gets_its_own_rotation_of_the_sample_set() {
    // Facing the edge of a wall that covers x < 0 only: which directions it blocks depends
    // on both sample coordinates, so different seeds give different 64-sample estimates
    // (each close to the 2048-sample one); the same seed repeats exactly. (Over a whole
    // wall the stratified set is exact for every rotation.)
    let asset = full_cube();
    let wall = boxed(DVec3::new(-100.0, -50.0, -1.0), DVec3::new(0.0, 50.0, 0.0));
    let inst = [placed(&asset, wall)];
    let tracer = Tracer::new(&inst);
    let params = LightingParams {
        max_distance: 1.0,
        shadow_aperture: 10.0,
        near: 1e-6,
    };
    let light = light_along(DVec3::Z);
    let p = DVec3::new(0.2, 0.0, 0.5);
    let ao = |seed: u64, n: u32| monte_carlo(&tracer, &light, &params, p, -DVec3::Z, n, seed).ao;
    let values: Vec<f32> = (0..8).map(|s| ao(s, 64)).collect();
    assert_eq!(ao(3, 64), values[3]);
    let distinct = values.iter().filter(|&&v| v != values[0]).count();
    assert!(distinct >= 3, "{values:?}");
    let truth = ao(0, 2048);
    assert!(
        values.iter().all(|v| (v - truth).abs() < 0.05),
        "{values:?} vs {truth}"
    );
}

/// AO facing the edge of a half-wall, by quadrature over the cosine-weighted hemisphere
/// with analytic plane hits (no voxels, no sampling code shared with the reference): the
/// wall is the slab `-1 <= z <= 0` where coordinate `axis` is negative (its top face and
/// its side face at `axis = 0` both block); the receiver at `p` faces -Z.
fn half_wall_ao(p: DVec3, max: f64, axis: usize) -> f64 {
    let n = 400;
    let mut open = 0.0;
    for i in 0..n {
        for j in 0..n {
            let u = (f64::from(i) + 0.5) / f64::from(n);
            let v = (f64::from(j) + 0.5) / f64::from(n);
            let (r, phi) = (u.sqrt(), std::f64::consts::TAU * v);
            let d = DVec3::new(r * phi.cos(), r * phi.sin(), -(1.0 - u).sqrt());
            let t_top = p.z / -d.z;
            let top = t_top <= max && (p + d * t_top)[axis] < 0.0;
            let t_side = -p[axis] / d[axis];
            let z_side = p.z + d.z * t_side;
            let side = d[axis] < 0.0 && t_side <= max && (-1.0..=0.0).contains(&z_side);
            if !(top || side) {
                open += 1.0;
            }
        }
    }
    open / f64::from(n * n)
}

#[test]
fn ao_beside_the_edge_of_a_half_wall_matches_quadrature_on_both_axes() {
    // Offset from the edge, so a mirrored or distorted sample set changes the answer.
    let asset = full_cube();
    let light = light_along(DVec3::Z);
    for (lo, hi, p, axis) in [
        (
            DVec3::new(-100.0, -50.0, -1.0),
            DVec3::new(0.0, 50.0, 0.0),
            DVec3::new(0.2, 0.0, 0.5),
            0,
        ),
        (
            DVec3::new(-50.0, -100.0, -1.0),
            DVec3::new(50.0, 0.0, 0.0),
            DVec3::new(0.0, 0.3, 0.4),
            1,
        ),
    ] {
        let inst = [Instance {
            lod: &asset.lods[2],
            object_to_world: boxed(lo, hi),
            faces: None,
        }];
        let got = f64::from(lit_at(&inst, &light, p, -DVec3::Z, 1.0).ao);
        let want = half_wall_ao(p, 1.0, axis);
        assert!((got - want).abs() < 0.01, "{p}: {got} vs {want}");
        assert!(want > 0.6 && want < 0.95, "{want}");
    }
}

#[test]
fn the_near_offset_lifts_ray_origins_along_the_normal() {
    // Facing the wall from 0.3: the normal points at the wall (-Z), so `near` = 0.1 moves
    // the origins to 0.2 from it: AO = 0.2² (0.4² if they moved the other way).
    let asset = full_cube();
    let wall = boxed(DVec3::new(-50.0, -50.0, -1.0), DVec3::new(50.0, 50.0, 0.0));
    let inst = [placed(&asset, wall)];
    let params = LightingParams {
        max_distance: 1.0,
        shadow_aperture: 10.0,
        near: 0.1,
    };
    let s = monte_carlo(
        &Tracer::new(&inst),
        &light_along(DVec3::Z),
        &params,
        DVec3::new(12.5, 12.5, 0.3),
        -DVec3::Z,
        4096,
        1,
    );
    assert!((f64::from(s.ao) - 0.04).abs() < 0.005, "{}", s.ao);
}

#[test]
fn a_coloured_oblique_light_and_a_shadowed_source_scale_the_bounce() {
    // The lit-wall bounce with a coloured light at 36.87° from the wall's normal
    // (ndl = 0.8): each channel is albedo · colour · 0.8 · blocked. Then a slab between the
    // wall and the light (out of the receiver's AO reach) shadows the wall: no bounce.
    let asset = full_cube();
    let wall = boxed(DVec3::new(-50.0, -50.0, -1.0), DVec3::new(50.0, 50.0, 0.0));
    let lod = &asset.lods[2];
    let inst = [Instance {
        lod,
        object_to_world: wall,
        faces: None,
    }];
    let light = Light {
        direction: [0.0, 0.6, 0.8],
        color: [0.5, 0.8, 2.0],
        ..Light::default()
    };
    let p = DVec3::new(12.5, 12.5, 0.5);
    let s = lit_at(&inst, &light, p, -DVec3::Z, 1.0);
    let tracer = Tracer::new(&inst);
    let (albedo, _) = tracer.surface(&tracer.trace(p, -DVec3::Z).unwrap());
    for ((a, c), got) in albedo.iter().zip(light.color).zip(s.indirect) {
        let want = f64::from(a * c) * 0.8 * 0.75;
        let got = f64::from(got);
        assert!((got - want).abs() < 0.01 * want.max(1.0), "{got} vs {want}");
    }
    let slab = boxed(
        DVec3::new(-100.0, -100.0, 3.0),
        DVec3::new(100.0, 100.0, 4.0),
    );
    let shaded = [
        inst[0],
        Instance {
            lod,
            object_to_world: slab,
            faces: None,
        },
    ];
    let s = lit_at(&shaded, &light, p, -DVec3::Z, 1.0);
    assert_eq!(s.indirect, [0.0; 3]);
    assert!((s.ao - 0.25).abs() < 0.01, "{}", s.ao);
}

#[test]
fn a_soft_shadow_partly_covered_matches_quadrature_over_the_light_cone() {
    // A slab over x < 0 at height 1..2 and a receiver 0.05 to its lit side: the light's
    // 20° cone (straight up) is partly covered. The reference's uniform cone sampling
    // against a quadrature of the same cone with an analytic slab hit.
    let asset = full_cube();
    let slab = boxed(DVec3::new(-100.0, -100.0, 1.0), DVec3::new(0.0, 100.0, 2.0));
    let inst = [placed(&asset, slab)];
    let params = LightingParams {
        max_distance: 0.5,
        shadow_aperture: 20.0,
        near: 1e-6,
    };
    let p = DVec3::new(0.05, 0.0, 0.0);
    let s = monte_carlo(
        &Tracer::new(&inst),
        &light_along(DVec3::Z),
        &params,
        p,
        DVec3::Z,
        4096,
        5,
    );
    // Uniform in solid angle: cos θ uniform in [cos 10°, 1]; the ray meets the slab's
    // bottom (z = 1) at x = p.x + tan θ cos φ, or its side (x = 0) below z = 2.
    let cos_max = 10f64.to_radians().cos();
    let n = 400;
    let mut lit = 0.0;
    for i in 0..n {
        for j in 0..n {
            let c = 1.0 - (f64::from(i) + 0.5) / f64::from(n) * (1.0 - cos_max);
            let phi = std::f64::consts::TAU * (f64::from(j) + 0.5) / f64::from(n);
            let sin = (1.0 - c * c).sqrt();
            let d = DVec3::new(sin * phi.cos(), sin * phi.sin(), c);
            let bottom = p.x + d.x / d.z < 0.0;
            let side = d.x < 0.0 && p.z + d.z * (-p.x / d.x) <= 2.0;
            if !(bottom || side) {
                lit += 1.0;
            }
        }
    }
    let want = lit / f64::from(n * n);
    assert!(want > 0.5 && want < 0.8, "{want}");
    assert!(
        (f64::from(s.shadow) - want).abs() < 0.01,
        "{} vs {want}",
        s.shadow
    );
}
