//! Lattice rays: the exact tie rules of every ray-walking shader, per pixel, against the
//! CPU reference (`ssbvb_voxel::reference::dda`, "Tie rule" and "Face normal").
//!
//! Elsewhere every camera is in general position, so no ray ever passes exactly through a
//! voxel edge or corner and a broken tie rule goes unnoticed. Here the cameras sit on cell
//! planes and look along axes or diagonals, and the pixels compared are the ones whose ray
//! is symmetric in f32 on the GPU exactly as in f64 on the CPU:
//!
//! - With a camera looking along an axis of a square image, pixel `(i, i)` has
//!   `ndc_y = -ndc_x` bit for bit (the same product, then `q·2 − 1` against `1 − q·2`), so
//!   its ray has two equal-magnitude components; from a camera whose coordinates are cell
//!   planes it crosses the two planes of every edge it meets at the same computed time, on
//!   the GPU and on the CPU.
//! - On a 63-pixel axis, `31.5 · fl32(1 / 63)` rounds to 0.5, so the centre row and column
//!   have an exactly zero component too: rays that run inside a cell plane (two cells, or
//!   two objects, touched at once).
//! - A camera looking along a space diagonal has a centre ray with three equal components:
//!   through cell corners.
//!
//! Compared per lattice pixel, exactly: the instance, the voxel's cell and the entered face;
//! the depth to f32 rounding (1e-5 relative). Each view also counts its decisive pixels —
//! hits at a time when the ray touches two or more occupied cells, of one instance or of
//! two — so that no view can pass without deciding ties.
//!
//! The techniques and what they are held to:
//! - the filter with the exact march (`RayMarchFilter`, one slot per pixel; `unique_voxels`;
//!   the splat pipeline): every rule of the reference, at every lattice pixel;
//! - the fast march: the same except at decisive pixels, where it tests only the cell
//!   entered diagonally (its documented difference; the test shows it differs there);
//! - the dense DDA, the octree caster and ESVO step through an edge their own way (one axis
//!   at a time, or diagonally; see their shaders), so at decisive edge and corner pixels
//!   they are held only to hitting a voxel the ray touches no earlier than the reference's;
//!   everywhere else — instance ties, rays inside a plane, a camera inside a voxel, faces —
//!   to the reference exactly.

mod oracle;
mod scenes;

use ssbvb_gpu::scene::Scene;
use ssbvb_passes::measure::ssbvb::read_slots;
use ssbvb_tests::{Frame, ctx, read_geometric_normals, reference_of, render};
use ssbvb_voxel::reference::ReferenceImage;

use oracle::{at_edge, touching, walk_pixel};
use scenes::*;

const LEVEL: u32 = 4;
/// Odd, with `fl32(31.5 · fl32(1/63)) == 0.5`: the centre row and column are exact.
const N: u32 = 63;
/// The same for a view that needs only its centre pixel and diagonal.
const SMALL: u32 = 3;

/// One pixel's first hit, in terms both sides can state exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PixelHit {
    instance: u32,
    cell: [u32; 3],
    /// The entered face's world normal, rounded (faces are axis-aligned here).
    face: [i32; 3],
    t: f64,
}

fn rounded(n: [f32; 3]) -> [i32; 3] {
    n.map(|v| v.round() as i32)
}

/// How a technique's hits are read back.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Readback {
    /// The filter's slots, one per covered pixel.
    Slots,
    /// The filter's slots, one per distinct voxel (`unique_voxels`): each names the pixel
    /// that claimed it.
    UniqueSlots,
    /// A ray caster's G-buffer: the albedo word names object and cell.
    GBuffer,
}

/// Which first hit a technique must report at every lattice pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
enum TieRule {
    /// The reference's, exactly.
    Reference,
    /// The one `walk` finds (the dense DDA's own rule), exactly.
    Walk,
    /// The reference's, except where its hit lies on an edge or corner of cells (or the ray
    /// runs in a cell plane): there only no voxel before the reference's (a traversal that
    /// steps through ties its own way, not modelled here).
    ReferenceOffEdges,
}

struct Technique {
    name: &'static str,
    pipeline: String,
    readback: Readback,
    ties: TieRule,
}

fn replaced(src: &str, from: &str, to: &str) -> String {
    assert!(src.contains(from), "pipeline has no `{from}`");
    src.replace(from, to)
}

fn exact_filter_techniques() -> Vec<Technique> {
    let keep = r#"output: "color", keep: ["ssbvb", "billboard_draw"],"#;
    let unique = replaced(
        include_str!("../../../assets/pipelines/ssbvb_unique.ron"),
        "march: Fast",
        "march: Exact",
    );
    let splat = replaced(
        include_str!("../../../assets/pipelines/ssbvb_splat.ron"),
        "march: Fast",
        "march: Exact",
    );
    vec![
        Technique {
            name: "filter (exact, a slot per pixel)",
            pipeline: crate::empty_space::prefilter_pipeline(1024),
            readback: Readback::Slots,
            ties: TieRule::Reference,
        },
        Technique {
            name: "filter (exact, unique voxels)",
            pipeline: replaced(&unique, r#"output: "color","#, keep),
            readback: Readback::UniqueSlots,
            ties: TieRule::Reference,
        },
        Technique {
            name: "splat pipeline (exact march)",
            pipeline: replaced(&splat, r#"output: "color","#, keep),
            readback: Readback::UniqueSlots,
            ties: TieRule::Reference,
        },
    ]
}

fn ray_caster_techniques() -> Vec<Technique> {
    [
        ("dense DDA", DENSE_DDA, TieRule::Walk),
        ("octree", OCTREE, TieRule::ReferenceOffEdges),
        ("ESVO", ESVO, TieRule::ReferenceOffEdges),
    ]
    .into_iter()
    .map(|(name, src, ties)| Technique {
        name,
        pipeline: src.to_string(),
        readback: Readback::GBuffer,
        ties,
    })
    .collect()
}

const DENSE_DDA: &str = include_str!("../../../assets/pipelines/dense_dda.ron");
const OCTREE: &str = include_str!("../../../assets/pipelines/octree.ron");
const ESVO: &str = include_str!("../../../assets/pipelines/esvo.ron");

/// Per pixel, the technique's hit (`None`: not covered, or not known for this pixel).
fn read_hits(t: &Technique, f: &Frame, n: u32) -> Vec<Option<PixelHit>> {
    let mut hits = vec![None; (n * n) as usize];
    match t.readback {
        Readback::Slots | Readback::UniqueSlots => {
            let mut appended = std::collections::BTreeSet::new();
            for s in read_slots(ctx(), &f.renderer).unwrap() {
                let vis = f.scene.visible[s.instance as usize];
                // Unique voxels: one slot per (instance, voxel) in a frame.
                let fresh = appended.insert((s.instance, s.voxel.cell()));
                assert!(
                    fresh || matches!(t.readback, Readback::Slots),
                    "{}: voxel {:?} of instance {} appended twice",
                    t.name,
                    s.voxel.cell(),
                    s.instance
                );
                let h = &mut hits[s.pixel as usize];
                assert!(h.is_none(), "{}: pixel {} filled twice", t.name, s.pixel);
                // The slot's voxel is the one of its cell (its id picked the colour; one
                // instance per object here, so the scene index is the object).
                assert_eq!(
                    s.voxel.color,
                    color_word(vis.scene_index, s.voxel.cell()),
                    "{}: slot {s:?}",
                    t.name
                );
                *h = Some(PixelHit {
                    instance: vis.scene_index,
                    cell: s.voxel.cell(),
                    face: rounded(s.face_normal()),
                    t: s.t as f64,
                });
            }
        }
        Readback::GBuffer => {
            let albedo = f.read_u32("gbuffer_albedo");
            let pos = f.read_f32("gbuffer_position");
            let normals = read_geometric_normals(f);
            for (i, h) in hits.iter_mut().enumerate() {
                let a = albedo[i];
                if a == 0 {
                    continue;
                }
                let p = &pos[i * 4..i * 4 + 3];
                *h = Some(PixelHit {
                    instance: (a & 0xff) / 16,
                    cell: [(a & 0xff) % 16, (a >> 8) & 0xff, (a >> 16) & 0xff],
                    face: rounded(normals[i]),
                    t: (p[0] as f64).hypot(p[1] as f64).hypot(p[2] as f64),
                });
            }
        }
    }
    hits
}

fn reference_hits(r: &ReferenceImage) -> Vec<Option<PixelHit>> {
    r.hits
        .iter()
        .map(|h| {
            h.map(|h| PixelHit {
                instance: h.instance,
                cell: h.cell,
                face: rounded(h.face_normal),
                t: h.t,
            })
        })
        .collect()
}

/// The outcome of one technique on one view.
#[derive(Debug, Default)]
struct Tally {
    compared: usize,
    decisive: usize,
    mismatches: Vec<String>,
    /// Pixels where the technique's own rule (`TieRule::Walk`) differs from the reference.
    own_choices: usize,
}

fn same_hit(g: Option<PixelHit>, w: Option<PixelHit>) -> bool {
    match (g, w) {
        (None, None) => true,
        (Some(g), Some(w)) => {
            (g.instance, g.cell, g.face) == (w.instance, w.cell, w.face)
                && (g.t - w.t).abs() <= 1e-5 * w.t.max(1.0)
        }
        _ => false,
    }
}

fn compare(
    t: &Technique,
    scene: &Scene,
    v: &View,
    gpu: &[Option<PixelHit>],
    r: &ReferenceImage,
) -> Tally {
    let reference = reference_hits(r);
    let mut tally = Tally::default();
    for (x, y) in lattice_pixels(v.lattice, v.size) {
        let i = (y * v.size + x) as usize;
        let g = gpu[i];
        // A unique-voxel slot speaks for the pixel that claimed it only.
        if t.readback == Readback::UniqueSlots && g.is_none() {
            continue;
        }
        tally.compared += 1;
        tally.decisive +=
            r.hits[i].is_some_and(|h| h.t > 0.0 && touching(scene, h.position).len() >= 2) as usize;
        let want = match t.ties {
            TieRule::Reference => reference[i],
            TieRule::Walk => {
                let w = walk_pixel(scene, &v.camera, v.size, x, y);
                tally.own_choices += !same_hit(w, reference[i]) as usize;
                w
            }
            TieRule::ReferenceOffEdges => {
                let on_edge = r.hits[i].is_some_and(|h| at_edge(scene, &h));
                if on_edge && !same_hit(g, reference[i]) {
                    tally.own_choices += 1;
                    let t_ref = reference[i].map_or(0.0, |w| w.t);
                    if g.is_none_or(|g| g.t >= t_ref * (1.0 - 1e-5)) {
                        continue;
                    }
                }
                reference[i]
            }
        };
        if !same_hit(g, want) {
            tally.mismatches.push(format!(
                "{} / {}: pixel ({x}, {y}): gpu {g:?}, expected {want:?} (reference {:?})",
                t.name, v.name, reference[i]
            ));
        }
    }
    tally
}

/// Renders every view with every technique (one renderer per technique and scene) and
/// compares; returns the tallies per (technique, view).
fn run(techniques: &[Technique], scene: &Scene, views: &[View]) -> Vec<(String, String, Tally)> {
    let references: Vec<ReferenceImage> = views
        .iter()
        .map(|v| reference_of(scene, &v.camera, (v.size, v.size)))
        .collect();
    let mut out = Vec::new();
    for t in techniques {
        // One renderer per technique and image size, reused across views.
        let mut frame: Option<(u32, Frame)> = None;
        for (v, r) in views.iter().zip(&references) {
            let f = match frame.as_mut() {
                Some((size, f)) if *size == v.size => {
                    f.renderer
                        .render(ctx(), &mut f.scene, &v.camera, ssbvb_passes::Profiling::Off)
                        .unwrap();
                    ctx().wait_idle().unwrap();
                    let errs = ctx().take_uncaptured_errors();
                    assert!(errs.is_empty(), "wgpu errors: {errs:#?}");
                    f
                }
                _ => {
                    let size = (v.size, v.size);
                    let f = render(&t.pipeline, scene.clone(), &v.camera, size);
                    &mut frame.insert((v.size, f)).1
                }
            };
            let gpu = read_hits(t, f, v.size);
            let tally = compare(t, scene, v, &gpu, r);
            if tally.decisive > 0 || !tally.mismatches.is_empty() || v.size == N {
                eprintln!(
                    "{} / {}: {} lattice px compared, {} decisive, {} own choices, {} mismatches",
                    t.name,
                    v.name,
                    tally.compared,
                    tally.decisive,
                    tally.own_choices,
                    tally.mismatches.len()
                );
            }
            out.push((t.name.to_string(), v.name.clone(), tally));
        }
    }
    out
}

fn assert_no_mismatch(results: &[(String, String, Tally)]) {
    let all: Vec<&String> = results.iter().flat_map(|r| &r.2.mismatches).collect();
    assert!(all.is_empty(), "{} mismatches:\n{:#?}", all.len(), all);
}

#[test]
fn exact_filter_follows_every_tie_rule_on_lattice_rays() {
    let t = exact_filter_techniques();
    let mut results = run(&t, &random_scene(), &axis_views());
    results.extend(run(&t, &dense_random_scene(), &many_camera_views()));
    let touch_views = vec![
        view(
            "along the shared plane",
            [0.0, 0.0, 4.0],
            [0.0; 3],
            Lattice::Axis,
        ),
        view(
            "off centre",
            [0.25, -0.125, 4.0],
            [0.25, -0.125, 0.0],
            Lattice::Axis,
        ),
    ];
    results.extend(run(&t, &duplicates_scene(), &duplicates_views()));
    results.extend(run(&t, &touching_scene(), &touch_views));
    results.extend(run(&t, &nested_scene(), &[nested_view()]));
    results.extend(run(&t, &level_zero_scene(), &axis_views()[..2]));
    let (scene, views) = inside_scene_and_views();
    results.extend(run(&t, &scene, &views));
    for (scene, views) in corner_choice_scenes() {
        results.extend(run(&t, &scene, &views));
    }
    assert_no_mismatch(&results);
}

#[test]
fn ray_casters_follow_the_shared_tie_rules_on_lattice_rays() {
    let t = ray_caster_techniques();
    let mut results = run(&t, &random_scene(), &axis_views());
    results.extend(run(&t, &dense_random_scene(), &many_camera_views()));
    results.extend(run(&t, &duplicates_scene(), &duplicates_views()));
    let touch_views = vec![view(
        "along the shared plane",
        [0.0, 0.0, 4.0],
        [0.0; 3],
        Lattice::Axis,
    )];
    results.extend(run(&t, &touching_scene(), &touch_views));
    let (scene, views) = inside_scene_and_views();
    let (below_plane, other_views): (Vec<View>, Vec<View>) = views
        .into_iter()
        .partition(|v| v.name.contains("one float below"));
    results.extend(run(&t, &scene, &other_views));
    // ESVO moves the origin into [1, 2]^3 (`o / 2 + 1.5`), which rounds it to 2^-22 of the
    // box's half-size: a camera one float below a cell plane starts on the plane there, by
    // the paper's design. The other two start in the reference's cell.
    assert_eq!(t[2].name, "ESVO");
    results.extend(run(&t[..2], &scene, &below_plane));
    results.extend(run(&t, &empty_first_scene(), &axis_views()[..2]));
    // The dense DDA's CPU model walks `LEVEL` grids only.
    assert_eq!(t[0].name, "dense DDA");
    results.extend(run(&t[1..], &level_zero_scene(), &axis_views()[..2]));
    assert_no_mismatch(&results);
}

/// The fast march (`march: Fast`) drops the tie rules: it tests only the cell a ray enters
/// diagonally. On lattice rays that shows: it agrees with the reference everywhere but at
/// edges and corners, and there it differs at some pixels without ever reporting a voxel
/// before the reference's.
#[test]
fn fast_march_differs_from_the_reference_only_at_edges_and_never_earlier() {
    let filter = "RayMarchFilter(max_steps: 1024)";
    let pipeline = replaced(
        &crate::empty_space::prefilter_pipeline(1024),
        filter,
        "RayMarchFilter(max_steps: 1024, march: Fast)",
    );
    let t = [Technique {
        name: "filter (fast march)",
        pipeline,
        readback: Readback::Slots,
        ties: TieRule::ReferenceOffEdges,
    }];
    let mut results = run(&t, &random_scene(), &axis_views());
    results.extend(run(&t, &dense_random_scene(), &many_camera_views()));
    assert_no_mismatch(&results);
    let differing: usize = results.iter().map(|r| r.2.own_choices).sum();
    let decisive: usize = results.iter().map(|r| r.2.decisive).sum();
    eprintln!(
        "fast march: differs from the reference at {differing} lattice pixels ({decisive} decisive)"
    );
    // Measured on lavapipe: 62 pixels; with the exact march's tie loop switched on in the
    // fast march, 11. Half the measured count as the bound.
    assert!(
        differing >= 31,
        "the fast march resolved all but {differing} ties like the reference"
    );
}
