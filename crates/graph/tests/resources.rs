//! Resource declarations at and beyond their limits, sizes and bytes at a screen size,
//! usages derived from the slots, parameter defaults, and the typed edits: the checks the
//! mutation campaign (`docs/reliability.md`) found untested.

use ssbvb_graph::{
    BillboardMode, BillboardsParams, BufferLayout, CountDesc, Format, GraphError, PassKind,
    ResourceDesc, ResourceUsage, SizeDesc, SplatBillboardsParams, resolve_str,
};
use wgpu_types::{BufferUsages, TextureUsages};

const SSBVB: &str = include_str!("../../../assets/pipelines/ssbvb_unique.ron");

/// The SSBVB pipeline with `decl` as the declaration of the `color` output (a texture) or
/// of `billboard_draw` (a buffer): the error it gives, if any.
fn resource_error(name: &str, decl: &str) -> Option<String> {
    let line = SSBVB
        .lines()
        .find(|l| l.trim_start().starts_with(&format!("\"{name}\":")))
        .expect("declared");
    let src = SSBVB.replace(line, &format!("    \"{name}\": {decl},"));
    match resolve_str(&src, "t.ron") {
        Ok(_) => None,
        Err(e) => {
            let bad = e.errors.iter().find(
                |x| matches!(x, GraphError::BadResource { resource, .. } if resource == name),
            );
            Some(match bad {
                Some(GraphError::BadResource { message, at, .. }) => {
                    // Reported on the declaration's line.
                    let want = src.lines().position(|l| l.contains(decl)).unwrap() + 1;
                    assert_eq!(at.pos.map(|p| p.line), Some(want), "{e}");
                    message.clone()
                }
                _ => format!("other: {e}"),
            })
        }
    }
}

#[test]
fn resource_sizes_and_counts_are_checked_at_their_limits() {
    let texture = |size: &str| {
        resource_error(
            "color",
            &format!("Texture(format: Rgba8UnormSrgb, size: {size})"),
        )
    };
    for ok in [
        "ScreenScaled(0.001)",
        "ScreenScaled(16.0)",
        "Fixed(1, 1)",
        "Fixed(16384, 16384)",
    ] {
        assert_eq!(texture(ok), None, "{ok}");
    }
    for (bad, msg) in [
        (
            "ScreenScaled(0.0)",
            "ScreenScaled factor must be in (0, 16], got 0",
        ),
        (
            "ScreenScaled(16.5)",
            "ScreenScaled factor must be in (0, 16], got 16.5",
        ),
        (
            "ScreenScaled(-1.0)",
            "ScreenScaled factor must be in (0, 16], got -1",
        ),
        (
            "ScreenScaled(inf)",
            "ScreenScaled factor must be in (0, 16], got inf",
        ),
        (
            "Fixed(0, 4)",
            "Fixed size must be 1..=16384 texels per side, got 0x4",
        ),
        (
            "Fixed(4, 0)",
            "Fixed size must be 1..=16384 texels per side, got 4x0",
        ),
        ("Fixed(16385, 4)", "got 16385x4"),
        ("Fixed(4, 16385)", "got 4x16385"),
    ] {
        let got = texture(bad).unwrap_or_else(|| panic!("{bad} accepted"));
        assert!(got.contains(msg), "{bad}: {got}");
    }
    let buffer = |count: &str| {
        resource_error(
            "ssbvb",
            &format!("Buffer(layout: VoxelSlot, count: {count})"),
        )
    };
    for ok in [
        "ScreenPixelsScaled(0.5)",
        "ScreenPixelsScaled(16.0)",
        "Fixed(1)",
        "Fixed(2147483648)",
    ] {
        assert_eq!(buffer(ok), None, "{ok}");
    }
    for (bad, msg) in [
        (
            "ScreenPixelsScaled(0.0)",
            "ScreenPixelsScaled factor must be in (0, 16], got 0",
        ),
        (
            "ScreenPixelsScaled(17.0)",
            "ScreenPixelsScaled factor must be in (0, 16], got 17",
        ),
        ("Fixed(0)", "Fixed count must be 1..=2147483648, got 0"),
        (
            "Fixed(2147483649)",
            "Fixed count must be 1..=2147483648, got 2147483649",
        ),
    ] {
        let got = buffer(bad).unwrap_or_else(|| panic!("{bad} accepted"));
        assert!(got.contains(msg), "{bad}: {got}");
    }
    let draw = |count: &str| {
        resource_error(
            "billboard_draw",
            &format!("Buffer(layout: DrawIndirect, count: {count})"),
        )
    };
    assert_eq!(draw("Fixed(1)"), None);
    let got = draw("Fixed(2)").expect("two draws accepted");
    assert!(
        got.contains("a DrawIndirect buffer holds one draw, got count 2"),
        "{got}"
    );
}

#[test]
fn sizes_counts_and_bytes_at_a_screen_size() {
    assert_eq!(SizeDesc::Screen.resolve((640, 480)), (640, 480));
    assert_eq!(SizeDesc::ScreenScaled(0.5).resolve((641, 480)), (321, 240));
    assert_eq!(SizeDesc::ScreenScaled(0.001).resolve((100, 100)), (1, 1));
    assert_eq!(
        SizeDesc::ScreenScaled(16.0).resolve((2000, 10)),
        (16384, 160)
    );
    assert_eq!(SizeDesc::Fixed(7, 9).resolve((640, 480)), (7, 9));
    assert_eq!(CountDesc::ScreenPixels.resolve((640, 480)), 307_200);
    assert_eq!(
        CountDesc::ScreenPixelsScaled(0.5).resolve((641, 480)),
        321 * 240
    );
    assert_eq!(CountDesc::Fixed(5).resolve((640, 480)), 5);
    for (layout, size) in [
        (BufferLayout::VoxelSlot, 32),
        (BufferLayout::DrawIndirect, 16),
        (BufferLayout::DispatchIndirect, 12),
        (BufferLayout::U32, 4),
        (BufferLayout::Vec4F32, 16),
    ] {
        assert_eq!(layout.element_size(), size, "{layout:?}");
    }
    let tex = ResourceDesc::Texture {
        format: Format::Rgba16Float,
        size: SizeDesc::Fixed(10, 3),
    };
    assert_eq!(tex.bytes((1, 1)), 10 * 3 * 8);
    let buf = ResourceDesc::Buffer {
        layout: BufferLayout::VoxelSlot,
        count: CountDesc::ScreenPixels,
    };
    assert_eq!(buf.bytes((4, 5)), 4 * 5 * 32);
    // The SSBVB pipeline at 32x16: every resource's bytes, summed, with and without
    // aliasing (texels x bytes per texel; the SSBVB 32 bytes per pixel; one draw).
    let p = resolve_str(SSBVB, "ssbvb_unique.ron").unwrap();
    let px = 32 * 16;
    let texel_bytes: u64 = [16, 4, 4, 8, 16, 4, 8, 8, 4].iter().sum();
    let unaliased = px * texel_bytes + px * 32 + 16;
    let m = p.memory((32, 16));
    assert_eq!(m.unaliased, unaliased);
    let physical: u64 = p.physical.iter().map(|r| r.desc.bytes((32, 16))).sum();
    assert_eq!(m.aliased, physical);
    assert!(m.aliased < m.unaliased);
}

#[test]
fn usages_follow_the_slots_each_resource_is_bound_to() {
    let p = resolve_str(SSBVB, "ssbvb_unique.ron").unwrap();
    let usage = |name: &str| p.resources[p.resource(name).expect(name)].usage;
    let t = ResourceUsage::Texture;
    // Buffers are cleared and may be read back; the output texture is read back.
    let b = |u: BufferUsages| {
        ResourceUsage::Buffer(u | BufferUsages::COPY_DST | BufferUsages::COPY_SRC)
    };
    let ra = TextureUsages::RENDER_ATTACHMENT;
    let sampled = TextureUsages::TEXTURE_BINDING;
    assert_eq!(usage("color"), t(ra | TextureUsages::COPY_SRC));
    // Written as an attachment, then sampled by the filter.
    assert_eq!(usage("entry"), t(ra | sampled));
    // The depth-stencil is also sampled by the smoothing (its depth aspect).
    assert_eq!(usage("depth_stencil"), t(ra | sampled));
    assert_eq!(usage("prepass_depth"), t(ra));
    assert_eq!(usage("ssbvb"), b(BufferUsages::STORAGE));
    assert_eq!(
        usage("billboard_draw"),
        b(BufferUsages::STORAGE | BufferUsages::INDIRECT)
    );
    assert!(p.resource("no such resource").is_none());
    // `resource_of` names the resource bound to a pass's slot.
    let composite = p.passes.iter().find(|s| s.name == "composite").unwrap();
    let normal = composite.resource_of("normal").unwrap();
    assert_eq!(p.resources[normal].name, "smoothed_normal");
    assert!(composite.resource_of("nope").is_none());
}

#[test]
fn omitted_parameters_take_their_defaults() {
    let kind = |text: &str| -> PassKind {
        let src = format!(
            "Pipeline(resources: {{}}, passes: [(name: \"p\", kind: {text})], output: \"x\")"
        );
        // Resolution fails (no resources); the parsed kind is what matters.
        match ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
            .from_str::<ssbvb_graph::PipelineDesc>(&src)
        {
            Ok(d) => d.passes[0].kind.clone(),
            Err(e) => panic!("{text}: {e}"),
        }
    };
    for k in PassKind::all_defaults() {
        let name = k.name();
        let written = match k {
            PassKind::EmptySpacePrepass
            | PassKind::CompositeCompute
            | PassKind::Triangles
            | PassKind::Composite
            | PassKind::ConeComposite => name.to_string(),
            _ => format!("{name}()"),
        };
        assert_eq!(kind(&written), k, "{written}");
    }
    // The documented defaults, spelled out.
    match kind("RayMarchFilter()") {
        PassKind::RayMarchFilter(p) => assert_eq!((p.max_steps, p.unique_voxels), (1024, false)),
        k => panic!("{k:?}"),
    }
    match kind("Smooth()") {
        PassKind::Smooth(p) => assert_eq!((p.max_i, p.min_dist), (1.0, 0.5)),
        k => panic!("{k:?}"),
    }
    match kind("Billboards()") {
        PassKind::Billboards(p) => assert_eq!(p.size_scale, 1.0),
        k => panic!("{k:?}"),
    }
    match (kind("DenseDda()"), kind("OctreeRayCast()")) {
        (PassKind::DenseDda(d), PassKind::OctreeRayCast(o)) => {
            assert_eq!((d.max_steps, o.max_steps), (4096, 4096))
        }
        k => panic!("{k:?}"),
    }
}

#[test]
fn splat_billboards_take_the_billboards_parameters() {
    const SPLAT: &str = include_str!("../../../assets/pipelines/ssbvb_splat.ron");
    const WRITTEN: &str = "SplatBillboards(mode: Flat, size_scale: 1.0)";
    assert!(SPLAT.contains(WRITTEN));
    let ray_box = BillboardsParams {
        mode: BillboardMode::RayBox,
        size_scale: 1.5,
    };
    for (text, want) in [
        (WRITTEN, BillboardsParams::default()),
        ("SplatBillboards(mode: RayBox, size_scale: 1.5)", ray_box),
        ("SplatBillboards()", BillboardsParams::default()),
    ] {
        let p = resolve_str(&SPLAT.replace(WRITTEN, text), "ssbvb_splat.ron")
            .unwrap_or_else(|e| panic!("{text}: {e}"));
        let splat = p.passes.iter().find(|s| s.kind.name() == "SplatBillboards");
        assert_eq!(
            splat.map(|s| &s.kind),
            Some(&PassKind::SplatBillboards(SplatBillboardsParams(want))),
            "{text}"
        );
    }
}

#[test]
fn typed_edits_touch_exactly_what_they_name() {
    let p = resolve_str(SSBVB, "ssbvb_unique.ron").unwrap();
    let mut d = p.desc.clone();
    match d.resource_mut("ssbvb") {
        Some(ResourceDesc::Buffer { layout, .. }) => assert_eq!(*layout, BufferLayout::VoxelSlot),
        other => panic!("{other:?}"),
    }
    match d.resource_mut("color") {
        Some(ResourceDesc::Texture { format, .. }) => assert_eq!(*format, Format::Rgba8UnormSrgb),
        other => panic!("{other:?}"),
    }
    assert!(d.resource_mut("nope").is_none());
    let k = PassKind::Smooth(ssbvb_graph::SmoothParams {
        max_i: 2.0,
        min_dist: 0.25,
        copy_depth: false,
    });
    let q = p.with_pass_kind("smooth", &k).unwrap();
    assert_eq!(
        q.desc
            .passes
            .iter()
            .find(|x| x.name == "smooth")
            .unwrap()
            .kind,
        k
    );
    assert_eq!(
        q.passes.iter().find(|x| x.name == "smooth").unwrap().kind,
        k
    );
    // Other passes keep their kinds.
    assert_eq!(
        q.passes.iter().find(|x| x.name == "filter").unwrap().kind,
        p.passes.iter().find(|x| x.name == "filter").unwrap().kind
    );
}
