//! Resolution of pipeline files: the bundled SSBVB pipeline, and one test per error kind
//! asserting that the message names the culprit (pass, resource) and the line.

use ssbvb_graph::{GraphError, PipelineErrors, ResolvedPipeline, resolve_file, resolve_str};

const SSBVB: &str = include_str!("../../../assets/pipelines/ssbvb_unique.ron");

fn ok(src: &str) -> ResolvedPipeline {
    match resolve_str(src, "test.ron") {
        Ok(p) => p,
        Err(e) => panic!("expected a valid pipeline, got:\n{e}"),
    }
}

fn err(src: &str) -> PipelineErrors {
    match resolve_str(src, "test.ron") {
        Ok(p) => panic!("expected errors, got a pipeline:\n{}", p.describe((64, 64))),
        Err(e) => e,
    }
}

/// Line (1-based) of the first line of `src` containing `needle`.
fn line_of(src: &str, needle: &str) -> usize {
    src.lines()
        .position(|l| l.contains(needle))
        .expect("needle in source")
        + 1
}

fn assert_mentions(e: &PipelineErrors, parts: &[&str]) {
    let text = e.to_string();
    for p in parts {
        assert!(
            text.contains(p),
            "error text does not mention {p:?}:\n{text}"
        );
    }
}

#[test]
fn ssbvb_pipeline_resolves_in_the_expected_order() {
    let p = ok(SSBVB);
    let order: Vec<_> = p.passes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        order,
        [
            "empty_space",
            "filter",
            "triangles",
            "billboards",
            "smooth",
            "composite"
        ]
    );
    assert!(p.pruned_passes.is_empty());
    assert!(p.pruned_resources.is_empty());
    assert_eq!(p.resources[p.output].name, "color");
    // entry (first used by empty_space, last by filter) and gbuffer_position (triangles ..
    // composite) have one descriptor and disjoint lifetimes: they share memory.
    let entry = &p.resources[p.resource("entry").unwrap()];
    let pos = &p.resources[p.resource("gbuffer_position").unwrap()];
    assert_eq!(entry.physical, pos.physical);
    let m = p.memory((640, 480));
    assert_eq!(m.unaliased - m.aliased, 640 * 480 * 16);
    // Usages are derived from the slots: entry is written as an attachment and sampled.
    let text = p.describe((640, 480));
    for line in [
        "  1. filter (RayMarchFilter) reads [entry] writes [ssbvb, billboard_draw]",
        "  4. smooth (Smooth) reads [gbuffer_normal, depth_stencil] writes [smoothed_normal]",
        "  entry: texture 640x480 Rgba32Float (4915200 bytes), passes 0..=1, shares memory with gbuffer_position",
        "  prepass_depth: texture 640x480 Depth32Float (1228800 bytes), passes 0..=0",
        "  color: texture 640x480 Rgba8UnormSrgb (1228800 bytes), passes 5..=5, output",
        "  gbuffer_geometric_normal: texture 640x480 Rg16Float (1228800 bytes), passes 2..=3",
        "memory: 27033616 bytes in 10 physical resources (31948816 bytes without aliasing, 4915200 saved)",
    ] {
        assert!(
            text.lines().any(|l| l == line),
            "no line `{line}` in:\n{text}"
        );
    }
}

#[test]
fn resolve_file_reads_the_bundled_pipeline_and_reports_missing_files() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/pipelines/ssbvb_unique.ron"
    );
    resolve_file(std::path::Path::new(path)).expect("bundled pipeline resolves");
    let e = resolve_file(std::path::Path::new("/nonexistent/p.ron")).unwrap_err();
    assert!(matches!(e.errors[0], GraphError::Io { .. }));
    assert_mentions(&e, &["/nonexistent/p.ron"]);
}

#[test]
fn passes_not_reaching_the_output_are_pruned() {
    // A smoothing pass whose output nobody reads, and a resource nobody binds.
    let src = SSBVB
        .replace(
            r#""normal": "smoothed_normal""#,
            r#""normal": "gbuffer_normal""#,
        )
        .replace(
            r#""color":"#,
            r#""unused": Texture(format: R32Float, size: Screen),
    "color":"#,
        );
    let p = ok(&src);
    assert_eq!(p.pruned_passes, ["smooth"]);
    assert_eq!(p.pruned_resources, ["smoothed_normal", "unused"]);
    assert!(p.passes.iter().all(|q| q.name != "smooth"));
}

#[test]
fn syntax_error_has_line_and_column() {
    let src = SSBVB
        .replace(r#"writes: ["color"],"#, r#"writes: ["color"]"#)
        .replacen("output", "output output", 1);
    let e = err(&src);
    assert!(matches!(e.errors[0], GraphError::Syntax { .. }), "{e}");
    let pos = e.errors[0].loc().pos.expect("position");
    assert!(pos.line > 1 && pos.col >= 1, "{e}");
    assert_mentions(&e, &["test.ron:"]);
}

#[test]
fn unknown_pass_kinds_are_all_reported_with_suggestions() {
    let src = SSBVB
        .replace("kind: Composite,", "kind: Compsite,")
        .replace("kind: Triangles,", "kind: Trianglez,");
    let e = err(&src);
    assert_eq!(e.errors.len(), 2, "{e}");
    let composite = format!("test.ron:{}:", line_of(&src, "Compsite"));
    assert_mentions(
        &e,
        &[
            "`Compsite`",
            "did you mean `Composite`",
            "pass `composite`",
            &composite,
        ],
    );
    assert_mentions(
        &e,
        &[
            "`Trianglez`",
            "did you mean `Triangles`",
            "pass `triangles`",
        ],
    );
}

#[test]
fn read_with_no_producer_names_pass_resource_and_line() {
    let src = SSBVB.replace(
        r#"(name: "empty_space", kind: EmptySpacePrepass, writes: ["entry", "prepass_depth"]),"#,
        "",
    );
    let e = err(&src);
    let line = line_of(&src, r#"reads: ["entry"]"#);
    assert!(
        e.errors.iter().any(|x| matches!(x, GraphError::NoProducer { pass, resource, .. } if pass == "filter" && resource == "entry")),
        "{e}"
    );
    assert_mentions(
        &e,
        &[
            "pass `filter` reads resource `entry`",
            &format!("test.ron:{line}:"),
        ],
    );
}

#[test]
fn two_unordered_writers_are_an_error() {
    let src = SSBVB.replace(r#"after: ["triangles"],"#, "");
    let e = err(&src);
    assert_mentions(
        &e,
        &[
            "written by passes `triangles` and `billboards`",
            "after: [\"triangles\"]",
        ],
    );
    assert!(
        e.errors
            .iter()
            .all(|x| matches!(x, GraphError::UnorderedWriters { .. })),
        "{e}"
    );
}

#[test]
fn cycles_name_the_passes_on_them() {
    // The filter now also runs after composite, which (through billboards) depends on it.
    let src = SSBVB.replace(
        r#"writes: ["ssbvb", "billboard_draw"],"#,
        r#"writes: ["ssbvb", "billboard_draw"], after: ["composite"],"#,
    );
    let e = err(&src);
    let GraphError::Cycle { cycle, .. } = &e.errors[0] else {
        panic!("{e}")
    };
    for p in ["filter", "billboards", "composite"] {
        assert!(cycle.iter().any(|c| c == p), "{cycle:?}");
    }
    assert!(!cycle.iter().any(|c| c == "empty_space"), "{cycle:?}");
    assert_eq!(cycle.first(), cycle.last());
    assert_mentions(
        &e,
        &[
            "cycle between passes",
            &format!("test.ron:{}:", line_of(&src, r#"name: "filter""#)),
        ],
    );
    // A pass after itself.
    let src = SSBVB.replace(
        "kind: Composite,",
        r#"kind: Composite, after: ["composite"],"#,
    );
    assert_mentions(
        &err(&src),
        &["cycle between passes: composite -> composite"],
    );
}

#[test]
fn format_class_and_layout_mismatches_name_slot_and_resource() {
    let src = SSBVB.replace(
        r#""entry":            Texture(format: Rgba32Float"#,
        r#""entry":            Texture(format: Rgba8Unorm"#,
    );
    let e = err(&src);
    assert_mentions(
        &e,
        &[
            "slot `entry` accepts formats Rgba32Float",
            "resource `entry` is Rgba8Unorm",
        ],
    );
    assert!(
        e.errors.len() >= 2,
        "both the prepass and the filter see it: {e}"
    );

    let src = SSBVB.replace(
        r#""ssbvb":            Buffer(layout: VoxelSlot"#,
        r#""ssbvb":            Buffer(layout: U32"#,
    );
    assert_mentions(
        &err(&src),
        &["slot `ssbvb` needs buffer layout VoxelSlot", "layout U32"],
    );

    let src = SSBVB.replace(
        r#""billboard_draw":   Buffer(layout: DrawIndirect, count: Fixed(1))"#,
        r#""billboard_draw":   Texture(format: R32Uint, size: Screen)"#,
    );
    assert_mentions(
        &err(&src),
        &[
            "slot `billboard_draw` needs a storage buffer",
            "is a texture",
        ],
    );
}

#[test]
fn unknown_resources_slots_and_missing_slots() {
    let src = SSBVB.replace(r#"reads: ["entry"],"#, r#"reads: {"entry": "entyr"},"#);
    let e = err(&src);
    assert_mentions(
        &e,
        &[
            "pass `filter` uses resource `entyr`",
            "did you mean `entry`",
            &format!("test.ron:{}:", line_of(&src, "entyr")),
        ],
    );

    let src = SSBVB.replace(
        r#"reads: ["gbuffer_normal", "depth_stencil"],"#,
        r#"reads: ["gbuffer_normal", "depth_stencil", "color"],"#,
    );
    assert_mentions(
        &err(&src),
        &[
            "pass `smooth` (Smooth) has no slot `color` among its reads; its reads are: `gbuffer_normal`, `depth_stencil`",
        ],
    );
    // A duplicate resource is reported where it is declared the second time, after
    // other names (line 24 of the edited file).
    let src = SSBVB.replace(
        r#"    "color":            Texture(format: Rgba8UnormSrgb, size: Screen),"#,
        r#"    "color":            Texture(format: Rgba8UnormSrgb, size: Screen),
    "ssbvb":            Buffer(layout: VoxelSlot, count: ScreenPixels),"#,
    );
    let e = err(&src);
    assert_mentions(
        &e,
        &["test.ron:26:5: resource `ssbvb` is declared more than once"],
    );

    let src = SSBVB.replace(r#"writes: ["color"],"#, "");
    let e = err(&src);
    assert_mentions(
        &e,
        &["pass `composite` (Composite) does not bind its write slot `color`"],
    );
}

#[test]
fn attachment_sizes_must_agree() {
    let src = SSBVB.replace(
        r#""prepass_depth":    Texture(format: Depth32Float, size: Screen)"#,
        r#""prepass_depth":    Texture(format: Depth32Float, size: ScreenScaled(0.5))"#,
    );
    assert_mentions(
        &err(&src),
        &[
            "pass `empty_space`",
            "`entry` (Screen) and `prepass_depth` (ScreenScaled(0.5)) differ in size",
        ],
    );
}

#[test]
fn bad_declarations_are_reported_together() {
    let src = SSBVB
        .replace(
            "Smooth(max_i: 1.0, min_dist: 0.5)",
            "Smooth(max_i: -1.0, min_dist: 0.5)",
        )
        .replace(r#"count: Fixed(1)"#, "count: Fixed(0)")
        .replace(r#"name: "smooth","#, r#"name: "filter","#);
    let e = err(&src);
    assert_mentions(
        &e,
        &[
            "max_i must be a number >= 0",
            "resource `billboard_draw`: Fixed count",
            "pass `filter` is declared more than once",
        ],
    );
    assert!(e.errors.len() >= 3, "{e}");
    // The duplicate is reported where it is declared the second time.
    let dup = e
        .errors
        .iter()
        .find(|x| matches!(x, GraphError::DuplicatePass { .. }))
        .unwrap();
    let second = src
        .lines()
        .enumerate()
        .filter(|(_, l)| l.contains(r#"name: "filter""#))
        .nth(1)
        .unwrap()
        .0
        + 1;
    assert_eq!(dup.loc().pos.unwrap().line, second, "{e}");
}

#[test]
fn output_must_exist_be_a_texture_and_have_a_writer() {
    assert_mentions(
        &err(&SSBVB.replace(r#"output: "color""#, r#"output: "colour""#)),
        &[
            "output `colour` is not a declared resource",
            "did you mean `color`",
        ],
    );
    assert_mentions(
        &err(&SSBVB.replace(r#"output: "color""#, r#"output: "ssbvb""#)),
        &["output `ssbvb` must be a texture"],
    );
}

#[test]
fn unknown_after_suggests_a_pass() {
    let e = err(&SSBVB.replace(r#"after: ["triangles"]"#, r#"after: ["triangle"]"#));
    assert_mentions(
        &e,
        &[
            "pass `billboards` runs after `triangle`, which is not a pass",
            "did you mean `triangles`",
        ],
    );
}

/// Checks an error report of `src` given as `file`: at least one error, each naming the
/// file first and, where it has a line, a line of `src` (or just past its end).
fn assert_located(e: &PipelineErrors, file: &str, src: &str) {
    assert_eq!(e.file, file);
    assert!(!e.errors.is_empty(), "an error report without errors");
    let lines = src.lines().count().max(1) + 1;
    for err in &e.errors {
        let text = err.to_string();
        let rest = text
            .strip_prefix(file)
            .unwrap_or_else(|| panic!("`{text}` does not start with {file}"));
        assert!(!text.contains("panicked"), "{text}");
        if let Some(pos) = rest.strip_prefix(':') {
            let line: usize = pos
                .split(':')
                .next()
                .and_then(|l| l.parse().ok())
                .unwrap_or_else(|| panic!("`{text}`: no line after the file"));
            assert!(
                (1..=lines).contains(&line),
                "`{text}`: line {line} of {lines}"
            );
        }
    }
}

#[test]
fn garbage_never_panics() {
    // Truncations and byte edits of a real file give located errors, never a panic; a
    // truncation resolves only when it cut nothing but trailing space.
    let bytes = SSBVB.as_bytes();
    let whole = SSBVB.trim_end().len();
    let (mut cut_ok, mut edit_ok, mut edit_err) = (0, 0, 0);
    for cut in (0..bytes.len()).step_by(7) {
        let s = String::from_utf8_lossy(&bytes[..cut]);
        match resolve_str(&s, "cut.ron") {
            Ok(_) => {
                assert!(cut >= whole, "a file cut at byte {cut} of {whole} resolved");
                cut_ok += 1;
            }
            Err(e) => assert_located(&e, "cut.ron", &s),
        }
    }
    let full = resolve_str(SSBVB, "ssbvb_unique.ron").unwrap();
    for i in (0..bytes.len()).step_by(13) {
        let mut b = bytes.to_vec();
        b[i] = b"(){}[]\":,x0"[i % 11];
        let s = String::from_utf8_lossy(&b);
        match resolve_str(&s, "edit.ron") {
            // An edit inside a comment or a name can leave a valid pipeline: the same
            // passes, or the same number of them.
            Ok(p) => {
                assert!(
                    p.passes.len() + p.pruned_passes.len()
                        == full.passes.len() + full.pruned_passes.len(),
                    "byte {i}: a valid edit changed the number of passes"
                );
                edit_ok += 1;
            }
            Err(e) => {
                assert_located(&e, "edit.ron", &s);
                edit_err += 1;
            }
        }
    }
    println!("truncations resolved: {cut_ok}; edits resolved: {edit_ok}, refused: {edit_err}");
    assert!(edit_err > edit_ok, "most byte edits must be refused");
}

#[test]
fn watcher_keeps_the_last_good_pipeline_on_error() {
    use ssbvb_graph::{PipelineWatcher, ReloadOutcome};
    let dir = std::env::temp_dir().join(format!("ssbvb-watch-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("p.ron");
    std::fs::write(&path, SSBVB).unwrap();
    let mut w = PipelineWatcher::new(&path).unwrap();
    assert!(matches!(w.poll(), ReloadOutcome::Unchanged));
    // An invalid edit (different length, so the change is seen even within one mtime tick).
    std::fs::write(
        &path,
        SSBVB.replace("kind: Composite,", "kind: Compositee,"),
    )
    .unwrap();
    match w.poll() {
        ReloadOutcome::Failed(e) => assert!(e.to_string().contains("Compositee"), "{e}"),
        other => panic!("expected failure, got {other:?}"),
    }
    assert_eq!(w.current().passes.len(), 6, "previous pipeline kept");
    // A valid edit that prunes the smoothing pass.
    std::fs::write(
        &path,
        SSBVB.replace(
            r#""normal": "smoothed_normal""#,
            r#""normal": "gbuffer_normal""#,
        ),
    )
    .unwrap();
    assert!(matches!(w.poll(), ReloadOutcome::Reloaded));
    assert_eq!(w.current().pruned_passes, ["smooth"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn kept_resources_keep_their_writers_alive() {
    // Output the entry texture only: everything after the prepass is pruned...
    let src = SSBVB.replace(r#"output: "color""#, r#"output: "entry""#);
    let p = ok(&src);
    assert_eq!(
        p.passes.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(),
        ["empty_space"]
    );
    // ...unless the SSBVB is kept for readback.
    let src = SSBVB.replace(r#"output: "color""#, r#"output: "entry", keep: ["ssbvb"]"#);
    let p = ok(&src);
    assert_eq!(
        p.passes.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(),
        ["empty_space", "filter"]
    );
    let ssbvb = &p.resources[p.resource("ssbvb").unwrap()];
    assert_eq!(ssbvb.last_use, 1);
    assert_mentions(
        &err(&SSBVB.replace(r#"output: "color""#, r#"output: "color", keep: ["sbvb"]"#)),
        &[
            "`sbvb` (in `keep`) is not a declared resource",
            "did you mean `ssbvb`",
        ],
    );
}

#[test]
fn the_cube_raster_pipeline_resolves_and_merging_defaults_to_on() {
    let src = include_str!("../../../assets/pipelines/cube_raster.ron");
    let p = ok(src);
    let names: Vec<_> = p.passes.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["triangles", "cube_raster", "smooth", "composite"]);
    assert_eq!(
        p.passes[1].kind,
        ssbvb_graph::PassKind::CubeRaster(ssbvb_graph::CubeRasterParams {
            merge_full_nodes: true
        })
    );
    // With no parameter given (`CubeRaster()`) the kind merges full nodes.
    let bare = ok(&src.replace("CubeRaster(merge_full_nodes: true)", "CubeRaster()"));
    assert_eq!(bare.passes[1].kind, p.passes[1].kind);
}

/// Every parameter check of every kind: the error is `BadParameter`, names the pass, the
/// kind and the rule, and points at the pass's line.
#[test]
fn bad_parameters_name_pass_kind_rule_and_line() {
    const DENSE: &str = include_str!("../../../assets/pipelines/dense_dda.ron");
    const OCTREE: &str = include_str!("../../../assets/pipelines/octree.ron");
    const SPLAT: &str = include_str!("../../../assets/pipelines/ssbvb_splat.ron");
    const RASTAVOX: &str = include_str!("../../../assets/pipelines/rastavox.ron");
    let cases: [(&str, &str, &str, &str, &str); 12] = [
        (
            RASTAVOX,
            "RastaVox(pixel_error: 1.0)",
            "RastaVox(pixel_error: -1.0)",
            "RastaVox",
            "pixel_error must be a number from 0 to 4096, got -1",
        ),
        (
            RASTAVOX,
            "RastaVox(pixel_error: 1.0)",
            "RastaVox(pixel_error: NaN)",
            "RastaVox",
            "pixel_error must be a number from 0 to 4096, got NaN",
        ),
        (
            RASTAVOX,
            "RastaVox(pixel_error: 1.0)",
            "RastaVox(pixel_error: 5000.0)",
            "RastaVox",
            "pixel_error must be a number from 0 to 4096, got 5000",
        ),
        (
            SSBVB,
            "RayMarchFilter(max_steps: 1024, unique_voxels: true, march: Fast)",
            "RayMarchFilter(max_steps: 0, unique_voxels: true, march: Fast)",
            "RayMarchFilter",
            "max_steps must be at least 1",
        ),
        (
            SSBVB,
            "Billboards(mode: Flat, size_scale: 1.0)",
            "Billboards(mode: Flat, size_scale: 0.0)",
            "Billboards",
            "size_scale must be a positive number, got 0",
        ),
        (
            SSBVB,
            "Billboards(mode: Flat, size_scale: 1.0)",
            "Billboards(mode: Flat, size_scale: -2.5)",
            "Billboards",
            "size_scale must be a positive number, got -2.5",
        ),
        (
            SSBVB,
            "Smooth(max_i: 1.0, min_dist: 0.5)",
            "Smooth(max_i: 1.0, min_dist: -0.5)",
            "Smooth",
            "min_dist must be a number >= 0, got -0.5",
        ),
        (
            SSBVB,
            "Smooth(max_i: 1.0, min_dist: 0.5)",
            "Smooth(max_i: -1.0, min_dist: 0.5)",
            "Smooth",
            "max_i must be a number >= 0, got -1",
        ),
        (
            SSBVB,
            "Smooth(max_i: 1.0, min_dist: 0.5)",
            "Smooth(max_i: inf, min_dist: 0.5)",
            "Smooth",
            "max_i must be a number >= 0, got inf",
        ),
        (
            DENSE,
            "DenseDda(max_steps: 4096)",
            "DenseDda(max_steps: 0)",
            "DenseDda",
            "max_steps must be at least 1",
        ),
        (
            OCTREE,
            "OctreeRayCast(max_steps: 4096)",
            "OctreeRayCast(max_steps: 0)",
            "OctreeRayCast",
            "max_steps must be at least 1",
        ),
        (
            SPLAT,
            "SplatBillboards(mode: Flat, size_scale: 1.0)",
            "SplatBillboards(mode: Flat, size_scale: 0.0)",
            "SplatBillboards",
            "size_scale must be a positive number, got 0",
        ),
    ];
    for (base, from, to, kind, rule) in cases {
        assert!(base.contains(from), "{from} not in the bundled pipeline");
        let src = base.replace(from, to);
        let e = err(&src);
        let found = e.errors.iter().find_map(|x| match x {
            GraphError::BadParameter {
                at,
                kind: k,
                message,
                ..
            } if k == kind && message.contains(rule) => Some(at.clone()),
            _ => None,
        });
        let at = found.unwrap_or_else(|| panic!("{to}: no BadParameter `{rule}` in {e}"));
        let line = line_of(&src, to);
        assert_eq!(
            at.pos.map(|p| p.line),
            Some(line),
            "{to}: reported at {at}, written on line {line}"
        );
        assert_eq!(e.errors.len(), 1, "{to}: {e}");
    }
    // NaN is refused too (RON has no NaN literal; the check is on the typed value).
    let nan = ssbvb_graph::PassKind::Billboards(ssbvb_graph::BillboardsParams {
        mode: ssbvb_graph::BillboardMode::Flat,
        size_scale: f32::NAN,
    });
    assert_eq!(nan.parameter_problems().len(), 1);
}

/// Smaller rules the mutation campaign found untested (`docs/reliability.md`).
#[test]
fn keep_after_class_and_syntax_rules() {
    // A kept resource nobody writes.
    let src = SSBVB.replace("output: \"color\",", "output: \"color\",\n  keep: [\"entry2\"],")
        .replace(
            "\"color\":            Texture(format: Rgba8UnormSrgb, size: Screen),",
            "\"color\":            Texture(format: Rgba8UnormSrgb, size: Screen),\n    \"entry2\": Texture(format: Rgba32Float, size: Screen),",
        );
    assert_mentions(&err(&src), &["entry2", "is kept but written by no pass"]);

    // A pass whose output nobody reads stays alive when a live pass names it in `after`.
    let src = SSBVB
        .replace(
            "\"color\":            Texture(format: Rgba8UnormSrgb, size: Screen),",
            "\"color\":            Texture(format: Rgba8UnormSrgb, size: Screen),\n    \"scratch\": Texture(format: Rgba8UnormSrgb, size: Screen),",
        )
        .replace(
            "      reads: {\"albedo\": \"gbuffer_albedo\"",
            "      after: [\"extra\"],\n      reads: {\"albedo\": \"gbuffer_albedo\"",
        )
        .replace(
            "  ],\n  output:",
            "    (name: \"extra\", kind: Composite, reads: {\"albedo\": \"gbuffer_albedo\", \"normal\": \"gbuffer_normal\", \"position\": \"gbuffer_position\"}, writes: {\"color\": \"scratch\"}),\n  ],\n  output:",
        );
    let p = ok(&src);
    assert!(
        p.passes.iter().any(|s| s.name == "extra"),
        "{:?}",
        p.pruned_passes
    );
    let extra = p.passes.iter().position(|s| s.name == "extra").unwrap();
    let composite = p.passes.iter().position(|s| s.name == "composite").unwrap();
    assert!(extra < composite);

    // A buffer bound to a texture slot.
    let src = SSBVB.replace("reads: [\"entry\"],", "reads: {\"entry\": \"ssbvb\"},");
    let e = err(&src);
    assert!(
        e.errors
            .iter()
            .any(|x| matches!(x, GraphError::ClassMismatch { .. })),
        "{e}"
    );

    // A syntax error before an unknown kind: both are reported (the kinds are scanned in
    // the text; serde stops at its first error).
    let src = SSBVB.replace("kind: Composite", "kind: Compost").replacen(
        "size: Screen),",
        "size: Screen) oops,",
        1,
    );
    let e = err(&src);
    assert!(
        e.errors
            .iter()
            .any(|x| matches!(x, GraphError::UnknownKind { .. })),
        "{e}"
    );
    assert!(
        e.errors
            .iter()
            .any(|x| matches!(x, GraphError::Syntax { .. })),
        "{e}"
    );
}

/// RON's raw identifiers name the same kind (`r#Composite` is `Composite`), and an unknown
/// raw kind is reported by its name.
#[test]
fn raw_identifier_kinds_are_read_as_their_names() {
    let src = SSBVB.replace("kind: Composite", "kind: r#Composite");
    assert!(src.contains("r#Composite"));
    let p = ok(&src);
    assert!(
        p.passes
            .iter()
            .any(|s| s.kind == ssbvb_graph::PassKind::Composite)
    );
    let e = err(&SSBVB.replace("kind: Composite", "kind: r#Compost"));
    assert_mentions(
        &e,
        &["unknown pass kind `Compost`", "did you mean `Composite`"],
    );
}

#[test]
fn a_binding_list_of_the_wrong_type_says_what_is_expected() {
    let src = SSBVB.replacen(r#"reads: ["entry"],"#, "reads: 5,", 1);
    assert_ne!(src, SSBVB);
    let e = err(&src);
    assert_mentions(
        &e,
        &[
            r#"Expected a list of names ["a", "b"] or a map {"slot": "resource"}"#,
            "the unsigned integer `5`",
        ],
    );
    assert_eq!(
        e.errors[0].loc().pos.map(|p| p.line),
        Some(line_of(&src, "reads: 5"))
    );
}

#[test]
fn the_removed_second_proxy_layer_is_refused_by_name_and_false_still_loads() {
    let src = include_str!("../../../assets/pipelines/ssbvb_pixel.ron");
    let filter = "RayMarchFilter(max_steps: 1024, unique_voxels: false, march: Fast)";
    assert!(src.contains(filter));
    let off = src.replace(
        filter,
        "RayMarchFilter(max_steps: 1024, unique_voxels: false, march: Fast, peel: false)",
    );
    resolve_str(&off, "off.ron").unwrap();
    let on = src.replace(
        filter,
        "RayMarchFilter(max_steps: 1024, unique_voxels: false, march: Fast, peel: true)",
    );
    let e = resolve_str(&on, "on.ron").unwrap_err().to_string();
    assert!(
        e.contains("peel: true was removed") && e.contains("8c208c3"),
        "{e}"
    );
}
