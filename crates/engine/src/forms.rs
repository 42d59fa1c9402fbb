//! The one table of SSBVB pipeline forms ([`FORMS`]): each form's name, pipeline file,
//! what it is, what it needs of an adapter (its file's requirements; `cpu_only`), and what
//! the rule and the calibration know about it. `ssbvb render`, the viewer, the web page,
//! the bench, `ssbvb calibrate` and `xtask gpu-bench` all read this table.
//!
//! The rule ([`choose_among`]) takes the adapter a command would run on (the best allowed
//! adapter that fits some SSBVB form) and, on it, the first form the rule may choose whose
//! needs it meets. The forms are ordered by what the bench measured on every adapter class
//! measured so far (a CPU adapter, lavapipe; a data-centre GPU, the H200;
//! `docs/benchmarks.md`): the frame without billboards (each pixel's hit written at its
//! pixel) before rasterized billboards. The splatted billboards need what the pixel form
//! needs, so they are no fallback. The forms with the prepass in compute, and with the
//! smoothing and the composite in compute as well, are no rule's choice: only a calibration
//! that measured one fastest picks it. The paper's rasterized form stays one flag away.

use serde::Serialize;
use ssbvb_gpu::AdapterVerdict;

/// One SSBVB form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Form {
    /// Its name: the bench technique and what a user names it by (`ssbvb-direct`).
    pub name: &'static str,
    /// Pipeline file, relative to the assets folder.
    pub file: &'static str,
    /// What it is, in a reason.
    pub what: &'static str,
    /// Why the rule may choose it where it stands (`None`: only a calibration picks it).
    pub rule: Option<&'static str>,
    /// Only for CPU adapters (device type `Cpu`): measured fastest there and nowhere else
    /// yet (its work is fragment work, slow on data-centre GPUs).
    pub cpu_only: bool,
    /// Measured by `ssbvb calibrate`, which may make it the adapter's default.
    pub calibrated: bool,
}

impl Form {
    /// The pipeline file's stem (`ssbvb_direct`): how the web page's URL names it.
    pub fn stem(&self) -> &'static str {
        self.file
            .trim_start_matches("pipelines/")
            .trim_end_matches(".ron")
    }
}

/// Every SSBVB form, in the order of preference of the rule and the calibration (ties go
/// to the earlier).
pub const FORMS: [Form; 6] = [
    Form {
        name: "ssbvb-direct",
        file: "pipelines/ssbvb_direct.ron",
        what: "each pixel's hit written straight into the G-buffer by the march (no SSBVB)",
        rule: Some(
            "on a CPU adapter fragment work costs what compute work costs, so the march in \
             the fragment stage saves the SSBVB's append and splat (docs/benchmarks.md)",
        ),
        cpu_only: true,
        calibrated: true,
    },
    Form {
        name: "ssbvb-pixel",
        file: "pipelines/ssbvb_pixel.ron",
        what: "each pixel's hit written at its pixel (no billboard)",
        rule: Some(
            "the march in compute and no billboard, the stage that costs most where \
             fragment work is slow (docs/benchmarks.md)",
        ),
        cpu_only: false,
        calibrated: true,
    },
    Form {
        name: "ssbvb-compute",
        file: "pipelines/ssbvb_compute.ron",
        what: "the pixel form with the prepass in compute",
        rule: None,
        cpu_only: false,
        calibrated: true,
    },
    Form {
        name: "ssbvb-all-compute",
        file: "pipelines/ssbvb_all_compute.ron",
        what: "the pixel form with the prepass, the smoothing and the composite in compute",
        rule: None,
        cpu_only: false,
        calibrated: true,
    },
    Form {
        name: "ssbvb-splat",
        file: "pipelines/ssbvb_splat.ron",
        what: "billboards splatted in compute",
        rule: None,
        cpu_only: false,
        calibrated: true,
    },
    Form {
        name: "ssbvb-unique",
        file: "pipelines/ssbvb_unique.ron",
        what: "rasterized billboards",
        rule: Some("the paper's frame, for adapters the forms before it do not run on"),
        cpu_only: false,
        calibrated: true,
    },
];

/// The form named `name` (its name, `ssbvb-direct`, or its file's stem, `ssbvb_direct`).
pub fn by_name(name: &str) -> Option<&'static Form> {
    FORMS.iter().find(|f| f.name == name || f.stem() == name)
}

/// The forms the rule may choose, in its order.
pub fn rule_forms() -> Vec<Form> {
    FORMS.iter().copied().filter(|f| f.rule.is_some()).collect()
}

/// How the pipeline of a command was chosen (`pipeline_choice` in `render --json`).
#[derive(Debug, Clone, Serialize, PartialEq, Eq)]
pub struct PipelineChoice {
    /// The pipeline file used.
    pub pipeline: String,
    /// Who chose it: `flag` (`--pipeline`), `scene` (the scene file's `pipeline:`),
    /// `calibration` (`ssbvb calibrate`'s fastest on this adapter) or `adapter` (the rule
    /// of this module).
    pub by: &'static str,
    /// Why, in words.
    pub reason: String,
    /// The adapter the rule looked at (`name [backend, type]`); `None` unless `by` is
    /// `adapter` and one fits.
    pub adapter: Option<String>,
    /// What the choice passed over and why (an unreadable calibration file).
    #[serde(skip)]
    pub warnings: Vec<crate::Warning>,
}

impl PipelineChoice {
    /// The pipeline file as a path.
    pub fn path(&self) -> std::path::PathBuf {
        std::path::PathBuf::from(&self.pipeline)
    }

    /// One line for a report.
    pub fn line(&self) -> String {
        format!("pipeline {} ({})", self.pipeline, self.reason)
    }
}

/// The rule over `forms`, with `per_form[k]` every adapter's verdict on the `k`th form's
/// requirements (best first, the same adapters in the same order for every form), and
/// `file_of` the pipeline path a choice names: the first adapter that fits any form, and on
/// it the first form that fits; with the adapter's position and verdict. With none, the
/// last form, whose device creation then fails naming what every adapter lacks.
pub fn choose_among(
    forms: &[Form],
    under: &str,
    per_form: &[Vec<AdapterVerdict>],
    file_of: impl Fn(&Form) -> String,
) -> (PipelineChoice, Option<(usize, AdapterVerdict)>) {
    let adapters = per_form.iter().map(Vec::len).max().unwrap_or(0);
    for a in 0..adapters {
        // A form without a row of verdicts counts as one no adapter is listed for.
        let verdicts: Vec<Option<&AdapterVerdict>> = (0..forms.len())
            .map(|k| per_form.get(k).and_then(|v| v.get(a)))
            .collect();
        if !verdicts.iter().flatten().any(|v| v.allowed) {
            continue;
        }
        let suits = |k: usize, v: &AdapterVerdict| {
            v.allowed && v.verdict.fits() && (!forms[k].cpu_only || v.device_type == "Cpu")
        };
        let Some(k) = (0..forms.len()).find(|&k| verdicts[k].is_some_and(|v| suits(k, v))) else {
            continue;
        };
        let Some(adapter) = verdicts[k] else {
            continue;
        };
        let name = format!(
            "{} [{}, {}]",
            adapter.name, adapter.backend, adapter.device_type
        );
        let why = forms[k].rule.unwrap_or("measured fastest");
        let mut reason = format!("{} on {name}{under}: {why}", forms[k].what);
        for (f, v) in forms[..k].iter().zip(&verdicts) {
            let why_not = match v {
                None => "the adapter is not listed".to_string(),
                Some(v) if v.verdict.fits() && f.cpu_only => {
                    "measured faster on CPU adapters only".to_string()
                }
                Some(v) => format!("the adapter lacks {}", v.verdict.missing.join("; ")),
            };
            reason.push_str(&format!("; not {}: {why_not}", f.what));
        }
        let choice = PipelineChoice {
            pipeline: file_of(&forms[k]),
            by: "adapter",
            reason,
            adapter: Some(name),
            warnings: Vec::new(),
        };
        return (choice, Some((a, adapter.clone())));
    }
    // With no form given, the table's last (the paper's raster form).
    let last = forms.last().unwrap_or(&FORMS[FORMS.len() - 1]);
    let choice = PipelineChoice {
        pipeline: file_of(last),
        by: "adapter",
        reason: format!("no adapter fits any SSBVB form{under}"),
        adapter: None,
        warnings: Vec::new(),
    };
    (choice, None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ssbvb_gpu::Verdict;

    fn verdict(name: &str, allowed: bool, missing: &[&str]) -> AdapterVerdict {
        AdapterVerdict {
            name: name.into(),
            backend: "Vulkan".into(),
            device_type: "DiscreteGpu".into(),
            driver: "test 1.0".into(),
            allowed,
            verdict: Verdict {
                missing: missing.iter().map(|s| s.to_string()).collect(),
                ..Default::default()
            },
        }
    }

    /// The rule over the rule's forms, the two marched forms (the direct and the pixel
    /// form, listed first) answered from `pixel` and the raster form from `raster`.
    fn rule(
        under: &str,
        pixel: Vec<AdapterVerdict>,
        raster: Vec<AdapterVerdict>,
    ) -> (PipelineChoice, Option<(usize, AdapterVerdict)>) {
        let forms = rule_forms();
        let per_form: Vec<Vec<AdapterVerdict>> = (0..forms.len())
            .map(|k| {
                if k <= 1 {
                    pixel.clone()
                } else {
                    raster.clone()
                }
            })
            .collect();
        choose_among(&forms, under, &per_form, |f| f.file.to_string())
    }

    fn cpu(name: &str, missing: &[&str]) -> AdapterVerdict {
        AdapterVerdict {
            device_type: "Cpu".into(),
            ..verdict(name, true, missing)
        }
    }

    #[test]
    fn a_cpu_adapter_gets_the_direct_form_and_a_gpu_the_pixel_form_saying_why() {
        let c = rule("", vec![cpu("lavapipe", &[])], vec![cpu("lavapipe", &[])]).0;
        assert!(c.pipeline.ends_with("ssbvb_direct.ron"), "{c:?}");
        assert!(c.reason.contains("straight into the G-buffer"), "{c:?}");
        let g = rule(
            "",
            vec![verdict("gpu", true, &[])],
            vec![verdict("gpu", true, &[])],
        )
        .0;
        assert!(g.pipeline.ends_with("ssbvb_pixel.ron"), "{g:?}");
        assert!(
            g.reason
                .contains("not each pixel's hit written straight into the G-buffer by the march (no SSBVB): measured faster on CPU adapters only"),
            "{g:?}"
        );
        // A CPU adapter without what the marched forms need gets the raster form.
        let r = rule("", vec![cpu("cpu", &["x"])], vec![cpu("cpu", &[])]).0;
        assert!(r.pipeline.ends_with("pipelines/ssbvb_unique.ron"), "{r:?}");
    }

    #[test]
    fn the_pixel_form_is_chosen_where_it_fits() {
        let c = rule(
            "",
            vec![verdict("gpu", true, &[])],
            vec![verdict("gpu", true, &[])],
        )
        .0;
        assert!(c.pipeline.ends_with("ssbvb_pixel.ron"), "{c:?}");
        assert_eq!(c.by, "adapter");
        assert!(
            c.reason.contains("at its pixel (no billboard) on gpu"),
            "{c:?}"
        );
        assert_eq!(c.adapter.as_deref(), Some("gpu [Vulkan, DiscreteGpu]"));
    }

    #[test]
    fn an_adapter_that_lacks_the_pixel_forms_needs_gets_raster_billboards_and_says_why() {
        let c = rule(
            " under WebGPU's default limits",
            vec![verdict("gpu", true, &["9 storage buffers per stage"])],
            vec![verdict("gpu", true, &[])],
        )
        .0;
        assert!(c.pipeline.ends_with("pipelines/ssbvb_unique.ron"), "{c:?}");
        assert!(
            c.reason
                .contains("not each pixel's hit written at its pixel")
                && c.reason.contains("9 storage buffers per stage")
                && c.reason.contains("under WebGPU's default limits"),
            "{c:?}"
        );
    }

    #[test]
    fn the_best_adapter_wins_over_a_better_form_on_a_worse_one() {
        // The first adapter runs only the raster form, the second (software) the pixel one:
        // the command runs on the first, so the raster form is its default.
        let c = rule(
            "",
            vec![verdict("gpu", true, &["x"]), verdict("cpu", true, &[])],
            vec![verdict("gpu", true, &[]), verdict("cpu", true, &[])],
        )
        .0;
        assert!(c.pipeline.ends_with("pipelines/ssbvb_unique.ron"), "{c:?}");
        assert_eq!(c.adapter.as_deref(), Some("gpu [Vulkan, DiscreteGpu]"));
    }

    #[test]
    fn adapters_not_allowed_are_passed_over_and_none_fitting_says_so() {
        let (c, picked) = rule(
            "",
            vec![verdict("gpu", false, &[]), verdict("cpu", true, &[])],
            vec![verdict("gpu", false, &[]), verdict("cpu", true, &[])],
        );
        assert_eq!(
            picked.map(|(a, v)| (a, v.name)),
            Some((1, "cpu".to_string()))
        );
        assert!(c.pipeline.ends_with("ssbvb_pixel.ron"), "{c:?}");
        assert!(c.reason.contains("on cpu"), "{c:?}");
        let (none, picked) = rule(
            "",
            vec![verdict("gpu", true, &["a"])],
            vec![verdict("gpu", true, &["b"])],
        );
        assert!(
            none.pipeline.ends_with("pipelines/ssbvb_unique.ron"),
            "{none:?}"
        );
        assert!(none.reason.contains("no adapter fits"), "{none:?}");
        assert_eq!(none.adapter, None);
        assert!(picked.is_none());
    }

    #[test]
    fn the_table_names_each_form_once_and_every_file_exists() {
        let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        for (i, f) in FORMS.iter().enumerate() {
            assert!(assets.join(f.file).is_file(), "{}", f.file);
            assert_eq!(by_name(f.name), Some(f));
            assert_eq!(by_name(f.stem()), Some(f));
            assert!(
                FORMS[..i]
                    .iter()
                    .all(|g| g.name != f.name && g.file != f.file),
                "{} twice",
                f.name
            );
        }
        let rule: Vec<&str> = rule_forms().iter().map(|f| f.name).collect();
        assert_eq!(rule, ["ssbvb-direct", "ssbvb-pixel", "ssbvb-unique"]);
        assert_eq!(by_name("esvo"), None);
    }
}
