//! The techniques `ssbvb bench` compares: each a bundled pipeline file, optionally with
//! one pass parameter changed, and the finest level it supports. Adding a technique is one
//! entry in [`TECHNIQUES`].

use anyhow::Result;
use ssbvb_graph::PassKind;

use crate::args::{BenchArgs, Preset};

/// Where a technique's pipeline comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PipelineSource {
    /// A bundled pipeline file (in `assets/pipelines`).
    File(&'static str),
    /// The SSBVB form of that name in the engine's table ([`ssbvb_engine::FORMS`]).
    Form(&'static str),
    /// The SSBVB form `render` chooses on this adapter ([`ssbvb_engine::choice`]).
    AdapterDefault,
    /// A bundled pipeline file with its smoothing and composite in compute
    /// ([`super::pipelines::with_shared_stages_in_compute`]).
    SharedStagesInCompute(&'static str),
}

/// One benchmarked technique.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Technique {
    /// Name in reports and in `--techniques`.
    pub(crate) name: &'static str,
    /// Its pipeline.
    pub(crate) pipeline: PipelineSource,
    /// A parameter changed from the file's (returns whether it changed the kind).
    pub(crate) edit: Option<fn(&mut PassKind) -> bool>,
    /// Highest level the technique supports.
    pub(crate) max_level: u32,
}

/// Every technique, in report order.
pub(crate) const TECHNIQUES: &[Technique] = &[
    // What a user gets: the SSBVB form `render` chooses on this adapter.
    Technique {
        name: "ssbvb",
        pipeline: PipelineSource::AdapterDefault,
        edit: None,
        max_level: 16,
    },
    // The paper's frame: one billboard per covered pixel.
    Technique {
        name: "ssbvb-flat",
        pipeline: PipelineSource::File("ssbvb_flat.ron"),
        edit: None,
        max_level: 16,
    },
    // The paper's frame with rasterized billboards (`ssbvb_unique.ron`): each visible voxel
    // appended once.
    Technique {
        name: "ssbvb-unique",
        pipeline: PipelineSource::Form("ssbvb-unique"),
        edit: None,
        max_level: 16,
    },
    // The default frame (no billboard) with temporal anti-aliasing (jittered frames blended
    // into the reprojected history): its FLIP against the supersampled reference is the
    // point.
    Technique {
        name: "ssbvb-aa",
        pipeline: PipelineSource::File("ssbvb_aa.ron"),
        edit: None,
        max_level: 16,
    },
    // The SSBVB frame with the billboards splatted in compute.
    Technique {
        name: "ssbvb-splat",
        pipeline: PipelineSource::Form("ssbvb-splat"),
        edit: None,
        max_level: 16,
    },
    // No billboard: each pixel's hit written at its pixel (`SplatBillboards(mode: Pixel)`).
    Technique {
        name: "ssbvb-pixel",
        pipeline: PipelineSource::Form("ssbvb-pixel"),
        edit: None,
        max_level: 16,
    },
    // No SSBVB: the march writes each pixel's hit straight into the G-buffer
    // (`RayMarchGBuffer`).
    Technique {
        name: "ssbvb-direct",
        pipeline: PipelineSource::Form("ssbvb-direct"),
        edit: None,
        max_level: 16,
    },
    // The same with the empty-space prepass in compute (`EmptySpaceCompute`): no raster
    // work left in the SSBVB's own stages.
    Technique {
        name: "ssbvb-compute",
        pipeline: PipelineSource::Form("ssbvb-compute"),
        edit: None,
        max_level: 16,
    },
    Technique {
        name: "dense-dda",
        pipeline: PipelineSource::File("dense_dda.ron"),
        edit: None,
        max_level: 8,
    },
    Technique {
        name: "octree",
        pipeline: PipelineSource::File("octree.ron"),
        edit: None,
        max_level: 16,
    },
    // The same octree traversed the ESVO way (Laine & Karras 2010, no contours).
    Technique {
        name: "esvo",
        pipeline: PipelineSource::File("esvo.ron"),
        edit: None,
        max_level: 16,
    },
    // The two octree casters tracing in a compute shader (the same image): the stronger
    // form of the baseline where fragment work is slow (docs/benchmarks.md, the H200).
    Technique {
        name: "octree-compute",
        pipeline: PipelineSource::File("octree.ron"),
        edit: Some(|k| match k {
            PassKind::OctreeRayCast(o) => {
                o.compute = true;
                true
            }
            _ => false,
        }),
        max_level: 16,
    },
    Technique {
        name: "esvo-compute",
        pipeline: PipelineSource::File("esvo.ron"),
        edit: Some(|k| match k {
            PassKind::EsvoRayCast(e) => {
                e.compute = true;
                true
            }
            _ => false,
        }),
        max_level: 16,
    },
    // Every stage that can be compute in compute: the SSBVB with the compute prepass and
    // ESVO's compute form, each with the smoothing and the composite in compute too (only
    // the triangles and the resolves stay rasterized), for adapters whose fragment work is
    // slow. The two are a pair: a stage both frames share is the same pass in both.
    Technique {
        name: "ssbvb-all-compute",
        pipeline: PipelineSource::Form("ssbvb-all-compute"),
        edit: None,
        max_level: 16,
    },
    Technique {
        name: "esvo-all-compute",
        pipeline: PipelineSource::SharedStagesInCompute("esvo.ron"),
        edit: Some(|k| match k {
            PassKind::EsvoRayCast(e) => {
                e.compute = true;
                true
            }
            _ => false,
        }),
        max_level: 16,
    },
    Technique {
        name: "cube-raster",
        pipeline: PipelineSource::File("cube_raster.ron"),
        edit: None,
        max_level: 16,
    },
    // RastaVox at pixel error 0 (every chunk at its finest level: comparable with the
    // exact techniques); `--preset rastavox` sweeps the pixel error.
    Technique {
        name: "rastavox",
        pipeline: PipelineSource::File("rastavox.ron"),
        edit: Some(|k| match k {
            PassKind::RastaVox(r) => {
                r.pixel_error = 0.0;
                true
            }
            _ => false,
        }),
        max_level: 16,
    },
];

/// The columns of `--preset paper`: SSBVB with rasterized billboards, the same with the
/// exact march (a removed technique, [`REMOVED`]: its keys stay in the preset's output,
/// empty), and every ray caster (the octree casters in both forms); then the SSBVB frame
/// with splatted billboards, the default SSBVB frame `render` chooses on this adapter, and
/// ESVO's compute form with the smoothing and the composite in compute too (the fair
/// baseline where a calibration made the default the all-compute form; appended: earlier
/// columns keep their order).
pub(crate) const PAPER_TECHNIQUES: &[&str] = &[
    "ssbvb-unique",
    "ssbvb-exact",
    "esvo",
    "octree",
    "dense-dda",
    "esvo-compute",
    "octree-compute",
    "ssbvb-splat",
    "ssbvb",
    "esvo-all-compute",
];

/// Techniques left out unless named: the direct form (the default `ssbvb` on a CPU adapter,
/// where CI runs), the compute forms of the octree casters (their fragment forms' images;
/// the paper preset runs them) and the all-compute pair (the images of their forms with
/// fragment smoothing; `gpu-bench` runs them).
const LEFT_OUT: &[&str] = &[
    "ssbvb-direct",
    "octree-compute",
    "esvo-compute",
    "ssbvb-all-compute",
    "esvo-all-compute",
];

/// Old technique names still accepted, with the name they go by now.
pub(crate) const RENAMED: &[(&str, &str)] = &[
    // The raster form with the fast march: the file's own setting.
    ("ssbvb-fast", "ssbvb-unique"),
];

/// Techniques that were experiments and left the product: knob settings no adapter's rule
/// or calibration picks (docs/benchmarks.md keeps what they measured).
pub(crate) const REMOVED: &[&str] = &[
    "ssbvb-raybox",
    "ssbvb-raybox-fast",
    "ssbvb-exact",
    "ssbvb-peel",
    "ssbvb-raster-aa",
    "ssbvb-edge-aa",
    "cube-raster-array",
];

/// The last revision that had the techniques of [`REMOVED`].
pub(crate) const REMOVED_AT: &str = "8c208c3";

/// The technique named `name` (or by its old name, said on stderr).
fn by_name(name: &str) -> Result<&'static Technique> {
    let current = match RENAMED.iter().find(|(old, _)| *old == name) {
        Some((old, new)) => {
            eprintln!("note: technique `{old}` is `{new}` now");
            *new
        }
        None => name,
    };
    if let Some(t) = TECHNIQUES.iter().find(|t| t.name == current) {
        return Ok(t);
    }
    if REMOVED.contains(&name) {
        anyhow::bail!(
            "technique `{name}` was an experiment and was removed (its numbers are in \
             docs/benchmarks.md; the code is at revision {REMOVED_AT}); known: {}",
            technique_names().join(", ")
        );
    }
    anyhow::bail!(
        "unknown technique `{name}`; known: {}",
        technique_names().join(", ")
    )
}

/// Technique names, for `--techniques`.
fn technique_names() -> Vec<&'static str> {
    TECHNIQUES.iter().map(|t| t.name).collect()
}

/// The techniques a run measures: those named with `--techniques` (an error names the
/// known ones), else all, or for the study all but the per-pixel SSBVB variants.
pub(crate) fn select(args: &BenchArgs) -> Result<Vec<&'static Technique>> {
    Ok(match &args.techniques {
        // The study's coarse models make cells span dozens of pixels: the per-pixel SSBVB
        // then draws each voxel once per pixel it covers, so the study runs the
        // unique-voxel SSBVB; name the others with --techniques to include them.
        None if matches!(args.preset, Preset::Study) => TECHNIQUES
            .iter()
            .filter(|t| t.name != "ssbvb-flat" && !LEFT_OUT.contains(&t.name))
            .collect(),
        // The paper compares SSBVB with ray casting.
        None if matches!(args.preset, Preset::Paper) => TECHNIQUES
            .iter()
            .filter(|t| PAPER_TECHNIQUES.contains(&t.name))
            .collect(),
        None => TECHNIQUES
            .iter()
            .filter(|t| !LEFT_OUT.contains(&t.name))
            .collect(),
        Some(names) => {
            let mut chosen: Vec<&'static Technique> = Vec::new();
            for n in names {
                let t = by_name(n)?;
                // An old name and its new one name one technique, measured once.
                if !chosen.iter().any(|c| c.name == t.name) {
                    chosen.push(t);
                }
            }
            chosen
        }
    })
}

/// The techniques named with `--techniques`, else those of `defaults` (a preset's own
/// set), in the table's order.
pub(crate) fn select_or(args: &BenchArgs, defaults: &[&str]) -> Result<Vec<&'static Technique>> {
    match &args.techniques {
        Some(_) => select(args),
        None => Ok(TECHNIQUES
            .iter()
            .filter(|t| defaults.contains(&t.name))
            .collect()),
    }
}

/// Whether `e` is a technique's refusal of the scene (too large, or a baseline's limits).
pub(crate) fn refused(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<ssbvb_passes::PassError>()
            .is_some_and(|e| e.is_too_large() || e.is_bad_scene())
            || matches!(
                c.downcast_ref::<ssbvb_gpu::ResourceError>(),
                Some(ssbvb_gpu::ResourceError::TooLarge(_) | ssbvb_gpu::ResourceError::BadScene(_))
            )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::harness::pipelines::technique_pipeline;
    use ssbvb_graph::ResolvedPipeline;

    /// An old name gives the technique it is now; a removed one says so and where its code
    /// is; an unknown one lists the current names only.
    #[test]
    fn old_names_removed_names_and_unknown_names() {
        assert_eq!(by_name("ssbvb-fast").unwrap().name, "ssbvb-unique");
        assert_eq!(by_name("esvo").unwrap().name, "esvo");
        let removed = by_name("ssbvb-peel").unwrap_err().to_string();
        assert!(
            removed.contains("was an experiment") && removed.contains(REMOVED_AT),
            "{removed}"
        );
        let unknown = by_name("ssbvb-nope").unwrap_err().to_string();
        assert!(
            unknown.contains("unknown technique `ssbvb-nope`"),
            "{unknown}"
        );
        let known = unknown.split("known: ").nth(1).unwrap();
        assert_eq!(known.split(", ").count(), TECHNIQUES.len());
        for (old, _) in RENAMED {
            assert!(!known.split(", ").any(|n| n == *old), "{known}");
        }
        // Names are unique and no current name is an old or removed one.
        for t in TECHNIQUES {
            assert_eq!(TECHNIQUES.iter().filter(|u| u.name == t.name).count(), 1);
            assert!(!REMOVED.contains(&t.name) && !RENAMED.iter().any(|r| r.0 == t.name));
        }
        assert!(TECHNIQUES.len() <= 17, "{} techniques", TECHNIQUES.len());
    }

    /// Every technique with a file of its own resolves with its edit.
    #[test]
    fn every_bundled_technique_resolves() {
        for t in TECHNIQUES {
            if !matches!(t.pipeline, PipelineSource::AdapterDefault) {
                technique_pipeline(t).unwrap_or_else(|e| panic!("{}: {e:#}", t.name));
            }
        }
    }

    /// The all-compute pair differ from their forms in the smoothing and the composite
    /// only, with the same parameters.
    #[test]
    fn the_all_compute_pair_differ_from_their_forms_in_the_shared_stages_only() {
        let find = |n: &str| TECHNIQUES.iter().find(|t| t.name == n).unwrap();
        for (all, form) in [
            ("ssbvb-all-compute", "ssbvb-compute"),
            ("esvo-all-compute", "esvo-compute"),
        ] {
            let a = technique_pipeline(find(all)).unwrap();
            let b = technique_pipeline(find(form)).unwrap();
            assert_eq!(a.passes.len(), b.passes.len());
            let mut swapped = 0;
            for (x, y) in a.passes.iter().zip(&b.passes) {
                match (&x.kind, &y.kind) {
                    (PassKind::SmoothCompute(c), PassKind::Smooth(f)) => {
                        assert_eq!((c.max_i, c.min_dist), (f.max_i, f.min_dist));
                        swapped += 1;
                    }
                    (PassKind::CompositeCompute, PassKind::Composite) => swapped += 1,
                    (k, l) => assert_eq!(k, l, "{all}: pass `{}`", x.name),
                }
            }
            assert_eq!(swapped, 2, "{all}");
        }
    }

    /// The bundled all-compute form (`ssbvb_compute.ron` included, two passes and the
    /// output replaced) is the shared-stages edit of the compute form, as ESVO's pair is.
    #[test]
    fn the_all_compute_form_file_is_the_shared_stages_edit_of_the_compute_form() {
        use crate::harness::pipelines::{bundled_pipeline, with_shared_stages_in_compute};
        let file = bundled_pipeline("ssbvb_all_compute.ron").unwrap();
        let edit =
            with_shared_stages_in_compute(&bundled_pipeline("ssbvb_compute.ron").unwrap()).unwrap();
        assert_eq!(file.desc, edit.desc);
        assert_eq!(file.sources.len(), 2, "{:?}", file.sources);
        let order = |p: &ResolvedPipeline| -> Vec<String> {
            p.passes.iter().map(|s| s.name.clone()).collect()
        };
        assert_eq!(order(&file), order(&edit));
    }
}
