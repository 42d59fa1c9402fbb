//! The pass kinds: one line each in the `pass_kinds!` list below, and one file per kind
//! with its parameter type (a unit struct for a kind without parameters), its defaults,
//! its [`KindSpec`] (stage, slots, entry points, parameter checks) and its constants.
//! `spec` defines what a kind declares and the macro; `formats` the formats and G-buffer
//! slots that several kinds share. Adding a kind here is half of adding a pass; the other
//! half is its implementation, registered in `ssbvb-passes`.

mod billboards;
mod composite;
mod cone_composite;
mod cone_trace;
mod cube_raster;
mod dense_dda;
mod edge_aa;
mod empty_space_compute;
mod empty_space_prepass;
mod esvo_ray_cast;
mod formats;
mod octree_ray_cast;
mod rastavox;
mod ray_march_filter;
mod ray_march_gbuffer;
mod shared;
mod smooth;
mod spec;
mod splat_billboards;
mod temporal;
mod triangles;
mod volume_slices;
mod writers;

pub use billboards::{BillboardMode, BillboardsParams};
pub use composite::{CompositeComputeKind, CompositeKind};
pub use cone_composite::ConeCompositeKind;
pub use cone_trace::{ConeTraceParams, MAX_CONES, MAX_VOLUME_RESOLUTION};
pub use cube_raster::CubeRasterParams;
pub use dense_dda::DenseDdaParams;
pub use edge_aa::EdgeAaParams;
pub use empty_space_compute::EmptySpaceComputeParams;
pub use empty_space_prepass::EmptySpacePrepassKind;
pub use esvo_ray_cast::EsvoRayCastParams;
pub use formats::LIGHT;
pub use octree_ray_cast::OctreeRayCastParams;
pub use rastavox::{MAX_PIXEL_ERROR, RastaVoxParams};
pub use ray_march_filter::{MarchMode, RayMarchFilterParams};
pub use ray_march_gbuffer::RayMarchGBufferParams;
pub use smooth::{SmoothComputeParams, SmoothParams};
pub use spec::{Access, KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};
pub use splat_billboards::SplatBillboardsParams;
pub use temporal::{MAX_LOD_BIAS, MAX_VARIANCE_CLIP, TemporalParams};
pub use triangles::TrianglesKind;
pub use volume_slices::{MAX_MIP_BIAS, MAX_SLICE_SPACING, MIN_SLICE_SPACING, VolumeSlicesParams};
pub use writers::{Writer, WritersRule};

use spec::pass_kinds;

pass_kinds! {
    /// Rasterizes the proxy meshes of visible objects: per pixel the object-space entry
    /// point and instance id (`entry`), with depth test against `prepass_depth`.
    EmptySpacePrepass = EmptySpacePrepassKind;
    /// Compute, one thread per pixel: marches the sparse lookup from the entry point to the
    /// first voxel and appends it to the SSBVB (`ssbvb`), counting hits into the indirect
    /// draw (`billboard_draw`).
    RayMarchFilter(RayMarchFilterParams);
    /// Draws one billboard per SSBVB entry (vertex pulling) into the G-buffer with
    /// stencil = voxel.
    Billboards(BillboardsParams);
    /// Ordinary triangle meshes into the G-buffer with stencil = triangle.
    Triangles = TrianglesKind;
    /// 3×3 Gaussian over normals with the paper's distance-dependent offset (Eq. 1),
    /// stencil-tested to voxel pixels.
    Smooth(SmoothParams);
    /// Deferred lighting (directional + ambient Blinn-Phong) into the output colour.
    Composite = CompositeKind;
    /// Baseline: per pixel, a plain cell-by-cell Amanatides–Woo DDA over a dense 3D texture
    /// of the visible object's LOD, writing the same G-buffer as the billboards (stencil =
    /// voxel).
    DenseDda(DenseDdaParams);
    /// Baseline: per pixel, a stack-based front-to-back ray cast through the sparse voxel
    /// octree of the visible object down to each instance's LOD level (the reference point
    /// of the paper, cf. Laine & Karras' ESVO), writing the same G-buffer as the billboards
    /// (stencil = voxel).
    OctreeRayCast(OctreeRayCastParams);
    /// Baseline: per pixel, Laine & Karras' ESVO traversal (coordinates in [1, 2]³, a
    /// parent stack indexed by scale, PUSH / ADVANCE / POP with the float-bit POP; no
    /// contours) through the same octree as `OctreeRayCast`, down to each instance's LOD
    /// level, writing the same G-buffer (stencil = voxel).
    EsvoRayCast(EsvoRayCastParams);
    /// Baseline, cube rasterization: instanced rasterization of one cube per voxel of each
    /// visible instance's LOD — or, with `merge_full_nodes`, one cube per completely full
    /// octree node — writing the same G-buffer as the billboards (stencil = voxel).
    CubeRaster(CubeRasterParams);
    /// The billboards as a compute splat (Schütz et al.'s compute rasterization, for
    /// adapters with weak raster units): per SSBVB entry, its quad's pixels take the
    /// nearest depth by atomic max, then the lowest entry at that depth, and a fullscreen
    /// resolve writes the same G-buffer as `Billboards` (stencil = voxel).
    SplatBillboards(SplatBillboardsParams);
    /// RastaVox: per visible chunk of each instance, the surface voxels of the coarsest
    /// OR-merged LOD within `pixel_error` pixels, at most three masked faces each by vertex
    /// pulling, writing the same G-buffer as the billboards (stencil = voxel).
    RastaVox(RastaVoxParams);
    /// Voxel cone tracing (Crassin et al. 2011), fullscreen: per G-buffer pixel, cones
    /// through the pre-filtered scene volume give ambient occlusion and a soft shadow
    /// (`occlusion`) and one diffuse bounce (`indirect`).
    ConeTrace(ConeTraceParams);
    /// Deferred lighting like `Composite`, with the cone tracer's occlusion, shadow and
    /// bounce.
    ConeComposite = ConeCompositeKind;
    /// Volumetric billboards: view-aligned slices through every RGBA volume, back to
    /// front, blended "over" the output colour and depth-tested against the opaque depth.
    VolumeSlices(VolumeSlicesParams);
    /// Temporal anti-aliasing: the history reprojected by the G-buffer's position, clamped
    /// to the current colour's neighbourhood and blended with it (the renderer jitters the
    /// projection of every frame while a pipeline has this pass).
    Temporal(TemporalParams);
    /// Single-frame anti-aliasing of the output colour for stills (FXAA-style): edge
    /// pixels blended with their neighbour across the edge by the share the edge covers.
    EdgeAa(EdgeAaParams);
    /// The empty-space prepass in compute, for adapters whose raster units are slow: the
    /// proxy meshes rasterized in software (nearest depth, then lowest triangle, by
    /// atomics), writing the same `entry` as `EmptySpacePrepass` into a storage texture.
    EmptySpaceCompute(EmptySpaceComputeParams);
    /// `Smooth` as a compute pass, for adapters whose fragment work is slow: the same
    /// image, with the stencil read as a texture instead of tested.
    SmoothCompute(SmoothComputeParams);
    /// `Composite` as a compute pass: the same lighting into an `Rgba8Unorm` storage
    /// texture, sRGB-encoded in the shader (the bytes an `Rgba8Unorm` `Composite` writes).
    CompositeCompute = CompositeComputeKind;
    /// The filter's march in a fragment shader over the prepass's tiles with a proxy, each
    /// pixel's hit written straight into the G-buffer (stencil = voxel): no SSBVB and no
    /// billboard, for adapters whose fragment work is as fast as their compute work.
    RayMarchGBuffer(RayMarchGBufferParams);
}

impl PassKind {
    /// The kind's parameters with their values as written in RON, in declaration order
    /// (`[("max_steps", "1024"), ("march", "Exact"), …]`; of a default kind, the
    /// defaults). Empty for a kind without parameters.
    pub fn parameter_values(&self) -> Vec<(String, String)> {
        let Ok(text) = ron::to_string(self) else {
            return Vec::new();
        };
        // `Name((a:1,b:Some(2)))`: peel parentheses until the fields are at the top.
        let mut body = text.strip_prefix(self.name()).unwrap_or_default();
        while let Some(inner) = body.strip_prefix('(').and_then(|b| b.strip_suffix(')')) {
            body = inner;
            if split_top_level(body)
                .iter()
                .all(|f| field_name(f).is_some())
            {
                break;
            }
        }
        split_top_level(body)
            .into_iter()
            .filter_map(|f| Some((field_name(f)?.to_string(), f.split_once(':')?.1.to_string())))
            .collect()
    }
}

/// The name of a RON field `name:value` (`None` when `text` is not one).
fn field_name(text: &str) -> Option<&str> {
    let (name, _) = text.split_once(':')?;
    (!name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
        .then_some(name)
}

/// `text` split at the commas outside parentheses.
fn split_top_level(text: &str) -> Vec<&str> {
    let (mut out, mut depth, mut start) = (Vec::new(), 0i32, 0);
    for (i, c) in text.char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    if start < text.len() {
        out.push(&text[start..]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference's parameters are the kinds' own fields, in order, each with a type
    /// and a range; a kind's description is its doc comment.
    #[test]
    fn every_parameter_is_described_and_has_its_default() {
        for kind in PassKind::all_defaults() {
            let values = kind.parameter_values();
            let names: Vec<&str> = values.iter().map(|(k, _)| k.as_str()).collect();
            let described: Vec<&str> = kind.parameters().iter().map(|p| p.name).collect();
            assert_eq!(names, described, "{}", kind.name());
            for p in kind.parameters() {
                assert!(!p.ty.is_empty() && !p.range.is_empty(), "{}", kind.name());
            }
            assert!(kind.description().len() > 20, "{}", kind.name());
        }
        let filter = PassKind::RayMarchFilter(RayMarchFilterParams::default());
        assert_eq!(
            filter.parameter_values(),
            [
                ("max_steps", "1024"),
                ("unique_voxels", "false"),
                ("march", "Exact"),
                ("peel", "false")
            ]
            .map(|(k, v)| (k.to_string(), v.to_string()))
        );
        let compute = PassKind::EmptySpaceCompute(EmptySpaceComputeParams {
            large_pixels: Some(64),
        });
        assert_eq!(
            compute.parameter_values(),
            [("large_pixels".to_string(), "Some(64)".to_string())]
        );
        assert!(PassKind::Composite.parameter_values().is_empty());
    }

    #[test]
    fn kind_names_match_variants_and_specs() {
        let names: Vec<_> = PassKind::all_defaults().iter().map(|k| k.name()).collect();
        assert_eq!(names, KIND_NAMES);
        let spec_names = [
            EmptySpacePrepassKind::NAME,
            RayMarchFilterParams::NAME,
            BillboardsParams::NAME,
            TrianglesKind::NAME,
            SmoothParams::NAME,
            CompositeKind::NAME,
            DenseDdaParams::NAME,
            OctreeRayCastParams::NAME,
            EsvoRayCastParams::NAME,
            CubeRasterParams::NAME,
            SplatBillboardsParams::NAME,
            RastaVoxParams::NAME,
            ConeTraceParams::NAME,
            ConeCompositeKind::NAME,
            VolumeSlicesParams::NAME,
            TemporalParams::NAME,
            EdgeAaParams::NAME,
            EmptySpaceComputeParams::NAME,
            SmoothComputeParams::NAME,
            CompositeComputeKind::NAME,
            RayMarchGBufferParams::NAME,
        ];
        assert_eq!(spec_names, KIND_NAMES);
    }

    #[test]
    fn slot_names_are_unique_per_kind() {
        for k in PassKind::all_defaults() {
            let mut names: Vec<_> = k.slots().iter().map(|s| s.name).collect();
            names.sort();
            names.dedup();
            assert_eq!(names.len(), k.slots().len(), "{}", k.name());
        }
    }

    #[test]
    fn parameters_are_found_only_in_their_kind() {
        let k = PassKind::RayMarchFilter(RayMarchFilterParams {
            max_steps: 0,
            unique_voxels: true,
            ..Default::default()
        });
        assert_eq!(RayMarchFilterParams::of_kind(&k).unwrap().max_steps, 0);
        assert!(DenseDdaParams::of_kind(&k).is_none());
        assert!(CompositeKind::of_kind(&PassKind::Composite).is_some());
        assert!(CompositeKind::of_kind(&k).is_none());
        assert_eq!(k.parameter_problems(), ["max_steps must be at least 1"]);
        assert_eq!(k.stage(), PassStage::Compute);
        assert!(PassKind::Composite.parameter_problems().is_empty());
    }

    #[test]
    fn entry_points_follow_the_stage() {
        // The compute kinds (the ray march filter, the compute prepass) name their kernels.
        let filter = PassKind::RayMarchFilter(RayMarchFilterParams::default());
        assert_eq!(filter.entry_points(), ["clear_draw", "main"]);
        for kind in PassKind::all_defaults() {
            match kind.stage() {
                PassStage::Render => {
                    assert_eq!(
                        kind.entry_points(),
                        ["vs_main", "fs_main"],
                        "{}",
                        kind.name()
                    )
                }
                PassStage::Compute => assert!(
                    [
                        "RayMarchFilter",
                        "EmptySpaceCompute",
                        "SmoothCompute",
                        "CompositeCompute"
                    ]
                    .contains(&kind.name()),
                    "{}",
                    kind.name()
                ),
            }
        }
        // A compute kind that lists nothing has the one `main`.
        struct OneKernel;
        impl KindSpec for OneKernel {
            const NAME: &'static str = "OneKernel";
            const STAGE: PassStage = PassStage::Compute;
            const SLOTS: &'static [SlotDesc] = &[];
        }
        assert_eq!(OneKernel::ENTRY_POINTS, ["main"]);
    }

    #[test]
    fn splat_billboards_are_written_like_billboards() {
        // As the resolver reads a pipeline file.
        let parse = |text: &str| {
            ron::Options::default()
                .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
                .from_str::<PassKind>(text)
                .unwrap_or_else(|e| panic!("{text}: {e}"))
        };
        let ray_box = BillboardsParams {
            mode: BillboardMode::RayBox,
            size_scale: 1.5,
        };
        for (splat, plain) in [
            ("SplatBillboards(mode: RayBox, size_scale: 1.5)", ray_box),
            ("SplatBillboards(size_scale: 1.5, mode: RayBox)", ray_box),
            ("SplatBillboards()", BillboardsParams::default()),
        ] {
            let want = PassKind::SplatBillboards(SplatBillboardsParams(plain));
            assert_eq!(parse(splat), want, "{splat}");
            let billboards = splat.replacen("SplatBillboards", "Billboards", 1);
            assert_eq!(
                parse(&billboards),
                PassKind::Billboards(plain),
                "{billboards}"
            );
        }
        let default = SplatBillboardsParams::default();
        assert_eq!(
            (default.mode, default.size_scale),
            (BillboardMode::Flat, 1.0)
        );
        // The same checks, and the same spelling of unknown fields, as `Billboards`.
        let bad = SplatBillboardsParams(BillboardsParams {
            size_scale: 0.0,
            ..Default::default()
        });
        assert_eq!(bad.problems(), bad.0.problems());
        assert_eq!(bad.problems().len(), 1);
        let unknown = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
            .from_str::<PassKind>("SplatBillboards(nope: 1)")
            .unwrap_err();
        assert!(
            unknown.to_string().contains("`nope` in `SplatBillboards`"),
            "{unknown}"
        );
    }
}
