//! The default SSBVB pipeline for the adapter at hand: what `render`, `view` and the bench's
//! `ssbvb` technique use when neither `--pipeline` nor the scene names one.
//!
//! The rule takes the adapter a command would run on (the best allowed adapter that fits
//! some SSBVB form, as [`crate::adapter_cmd::headless_context`] ranks them) and, on it, the
//! first form of [`FORMS`] whose needs it meets under the process's limits. The forms are
//! ordered by what the bench measured on every adapter class measured so far (a CPU adapter,
//! lavapipe; a data-centre GPU, the H200; `docs/benchmarks.md`): the frame without
//! billboards (each pixel's hit written at its pixel) before rasterized billboards. The
//! splatted billboards (`ssbvb_splat.ron`) need what the first form needs, so they are no
//! fallback. The forms with the prepass in compute too (`ssbvb_compute.ron`), and with the
//! smoothing and the composite in compute as well (`ssbvb_all_compute.ron`), are no rule's
//! choice: on lavapipe they are slower than the rasterized stages, and no GPU has measured
//! them yet, so only a calibration that measured one fastest picks it. The paper's rasterized
//! form stays one flag away (`--pipeline assets/pipelines/ssbvb.ron`).

use std::path::PathBuf;

use anyhow::Result;
use serde::Serialize;
use ssbvb_gpu::{AdapterVerdict, GpuContext, Requirements};

use crate::adapter_cmd::{limits, requirements_of, resolve};
use crate::bundled::assets_dir;

/// One SSBVB form the rule can choose.
#[derive(Debug, Clone, Copy)]
pub struct Form {
    /// Pipeline file, relative to the assets folder.
    pub file: &'static str,
    /// What it is, in a reason.
    pub name: &'static str,
    /// Why it stands where it does in [`FORMS`].
    pub why: &'static str,
    /// Only for CPU adapters (device type `Cpu`): measured fastest there and nowhere else
    /// yet (its work is fragment work, slow on data-centre GPUs).
    pub cpu_only: bool,
}

/// The SSBVB forms, fastest first on the adapters measured.
pub const FORMS: [Form; 3] = [
    Form {
        file: "pipelines/ssbvb_direct.ron",
        name: "each pixel's hit written straight into the G-buffer by the march (no SSBVB)",
        why: "the fastest SSBVB frame measured on lavapipe, a CPU adapter, where fragment \
              work costs what compute work costs (docs/benchmarks.md)",
        cpu_only: true,
    },
    Form {
        file: "pipelines/ssbvb_pixel.ron",
        name: "each pixel's hit written at its pixel (no billboard)",
        why: "the fastest compute-marched SSBVB frame measured; on the NVIDIA H200 the \
              billboards were the frame's costliest stage, and this form has none \
              (docs/benchmarks.md)",
        cpu_only: false,
    },
    Form {
        file: "pipelines/ssbvb.ron",
        name: "rasterized billboards",
        why: "the paper's frame",
        cpu_only: false,
    },
];

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
}

impl PipelineChoice {
    /// The pipeline file as a path.
    pub fn path(&self) -> PathBuf {
        PathBuf::from(&self.pipeline)
    }

    /// One line for a report.
    pub fn line(&self) -> String {
        format!("pipeline {} ({})", self.pipeline, self.reason)
    }
}

/// The pipeline of a command: `flag` (`--pipeline`), else the scene's, else the rule's
/// choice for this process's adapter and limits.
pub fn choose(flag: Option<PathBuf>, scene: Option<PathBuf>) -> Result<PipelineChoice> {
    if let Some(p) = flag {
        return Ok(PipelineChoice {
            pipeline: p.display().to_string(),
            by: "flag",
            reason: "named with --pipeline".into(),
            adapter: None,
        });
    }
    if let Some(p) = scene {
        return Ok(PipelineChoice {
            pipeline: p.display().to_string(),
            by: "scene",
            reason: "named by the scene file's `pipeline:`".into(),
            adapter: None,
        });
    }
    default_for_adapter()
}

/// The choice for this process's adapter and limits (made once per process: the limits
/// are set once, and the adapters do not change under a running command): the form
/// `ssbvb calibrate` measured fastest on this adapter, driver and limits, else the rule's.
pub fn default_for_adapter() -> Result<PipelineChoice> {
    static CHOICE: std::sync::OnceLock<PipelineChoice> = std::sync::OnceLock::new();
    if let Some(c) = CHOICE.get() {
        return Ok(c.clone());
    }
    let (rule, picked) = choose_among(&FORMS, under(), list_for)?;
    let c = match picked {
        Some((a, adapter)) => calibrated(rule, a, &adapter, &crate::calibration::path())?,
        None => rule,
    };
    Ok(CHOICE.get_or_init(|| c).clone())
}

/// `render`'s adapters' verdicts on some requirements under this process's limits.
fn list_for(_: usize, req: &Requirements) -> Vec<AdapterVerdict> {
    GpuContext::list_adapters(req, limits())
}

/// How a reason names the limits.
fn under() -> &'static str {
    match limits() {
        ssbvb_gpu::DeviceLimits::Adapter => "",
        ssbvb_gpu::DeviceLimits::WebGpuDefaults => " under WebGPU's default limits",
    }
}

/// `rule` unless the calibration file at `file` has an entry for `adapter` (the `a`th
/// listed) under this process's limits whose fastest form the adapter fits. An unreadable
/// calibration is ignored with a warning (printed, and said in the reason).
fn calibrated(
    mut rule: PipelineChoice,
    a: usize,
    adapter: &AdapterVerdict,
    file: &std::path::Path,
) -> Result<PipelineChoice> {
    let key = crate::calibration::AdapterKey::of(adapter, limits().name());
    let entry = match crate::calibration::load(file) {
        Ok(f) => f.and_then(|f| crate::calibration::lookup(&f, &key).cloned()),
        Err(e) => {
            let w =
                format!("the calibration was ignored ({e:#}); `ssbvb calibrate` measures again");
            eprintln!("warning: {w}");
            rule.reason.push_str(&format!("; {w}"));
            None
        }
    };
    let Some((entry, fastest)) = entry.and_then(|e| Some((e.clone(), e.fastest()?.to_string())))
    else {
        return Ok(rule);
    };
    let pipeline = resolve(&assets_dir().join(&fastest))?;
    let fits = list_for(0, &requirements_of(&[&pipeline]))
        .get(a)
        .is_some_and(|v| v.allowed && v.verdict.fits());
    if !fits {
        return Ok(rule);
    }
    Ok(PipelineChoice {
        pipeline: assets_dir().join(&fastest).display().to_string(),
        by: "calibration",
        reason: format!(
            "measured fastest on {} [{}, {}]{} by `ssbvb calibrate` ({})",
            adapter.name,
            adapter.backend,
            adapter.device_type,
            under(),
            entry.summary()
        ),
        adapter: rule.adapter,
    })
}

/// The adapter the rule picks (the best allowed one that fits any of its forms) and which
/// of `files` (pipeline files relative to the assets folder) it fits, in their order.
pub fn adapter_and_fitting_forms(
    files: &[&'static str],
) -> Result<(AdapterVerdict, Vec<&'static str>)> {
    let (_, picked) = choose_among(&FORMS, under(), list_for)?;
    let Some((a, adapter)) = picked else {
        anyhow::bail!("no adapter fits any SSBVB form{}", under());
    };
    let mut fitting = Vec::new();
    for f in files {
        let pipeline = resolve(&assets_dir().join(f))?;
        if list_for(0, &requirements_of(&[&pipeline]))
            .get(a)
            .is_some_and(|v| v.allowed && v.verdict.fits())
        {
            fitting.push(*f);
        }
    }
    Ok((adapter, fitting))
}

/// The rule over `forms`, with `list` giving every adapter's verdict on the `k`th form's
/// requirements (best first, the same adapters in the same order for every form): the
/// first adapter that fits any form, and on it the first form that fits; with the
/// adapter's position and verdict. With none, the last form, whose device creation then
/// fails naming what every adapter lacks.
pub(crate) fn choose_among(
    forms: &[Form],
    under: &str,
    list: impl Fn(usize, &Requirements) -> Vec<AdapterVerdict>,
) -> Result<(PipelineChoice, Option<(usize, AdapterVerdict)>)> {
    let mut per_form = Vec::with_capacity(forms.len());
    for (k, f) in forms.iter().enumerate() {
        let pipeline = resolve(&assets_dir().join(f.file))?;
        per_form.push(list(k, &requirements_of(&[&pipeline])));
    }
    let adapters = per_form.iter().map(Vec::len).max().unwrap_or(0);
    for a in 0..adapters {
        let verdicts: Vec<Option<&AdapterVerdict>> = per_form.iter().map(|v| v.get(a)).collect();
        if !verdicts.iter().flatten().any(|v| v.allowed) {
            continue;
        }
        let suits = |k: usize, v: &AdapterVerdict| {
            v.allowed && v.verdict.fits() && (!forms[k].cpu_only || v.device_type == "Cpu")
        };
        let Some(k) = (0..forms.len()).find(|&k| verdicts[k].is_some_and(|v| suits(k, v))) else {
            continue;
        };
        let adapter = verdicts[k].expect("found above");
        let name = format!(
            "{} [{}, {}]",
            adapter.name, adapter.backend, adapter.device_type
        );
        let mut reason = format!("{} on {name}{under}: {}", forms[k].name, forms[k].why);
        for (f, v) in forms[..k].iter().zip(&verdicts) {
            let why_not = match v {
                None => "the adapter is not listed".to_string(),
                Some(v) if v.verdict.fits() && f.cpu_only => {
                    "measured faster on CPU adapters only".to_string()
                }
                Some(v) => format!("the adapter lacks {}", v.verdict.missing.join("; ")),
            };
            reason.push_str(&format!("; not {}: {why_not}", f.name));
        }
        let choice = PipelineChoice {
            pipeline: assets_dir().join(forms[k].file).display().to_string(),
            by: "adapter",
            reason,
            adapter: Some(name),
        };
        return Ok((choice, Some((a, adapter.clone()))));
    }
    let last = forms.last().expect("at least one form");
    let choice = PipelineChoice {
        pipeline: assets_dir().join(last.file).display().to_string(),
        by: "adapter",
        reason: format!("no adapter fits any SSBVB form{under}"),
        adapter: None,
    };
    Ok((choice, None))
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

    /// A lister that answers the two marched forms (the direct and the pixel form, listed
    /// first) from `pixel` and the raster form from `raster`.
    fn lister(
        pixel: Vec<AdapterVerdict>,
        raster: Vec<AdapterVerdict>,
    ) -> impl Fn(usize, &Requirements) -> Vec<AdapterVerdict> {
        move |k, _| {
            if k <= 1 {
                pixel.clone()
            } else {
                raster.clone()
            }
        }
    }

    fn cpu(name: &str, missing: &[&str]) -> AdapterVerdict {
        AdapterVerdict {
            device_type: "Cpu".into(),
            ..verdict(name, true, missing)
        }
    }

    #[test]
    fn a_cpu_adapter_gets_the_direct_form_and_a_gpu_the_pixel_form_saying_why() {
        let c = choose_among(
            &FORMS,
            "",
            lister(vec![cpu("lavapipe", &[])], vec![cpu("lavapipe", &[])]),
        )
        .unwrap()
        .0;
        assert!(c.pipeline.ends_with("ssbvb_direct.ron"), "{c:?}");
        assert!(c.reason.contains("straight into the G-buffer"), "{c:?}");
        let g = choose_among(
            &FORMS,
            "",
            lister(
                vec![verdict("gpu", true, &[])],
                vec![verdict("gpu", true, &[])],
            ),
        )
        .unwrap()
        .0;
        assert!(g.pipeline.ends_with("ssbvb_pixel.ron"), "{g:?}");
        assert!(
            g.reason
                .contains("not each pixel's hit written straight into the G-buffer by the march (no SSBVB): measured faster on CPU adapters only"),
            "{g:?}"
        );
        // A CPU adapter without what the marched forms need gets the raster form.
        let r = choose_among(
            &FORMS,
            "",
            lister(vec![cpu("cpu", &["x"])], vec![cpu("cpu", &[])]),
        )
        .unwrap()
        .0;
        assert!(r.pipeline.ends_with("pipelines/ssbvb.ron"), "{r:?}");
    }

    #[test]
    fn the_pixel_form_is_chosen_where_it_fits() {
        let c = choose_among(
            &FORMS,
            "",
            lister(
                vec![verdict("gpu", true, &[])],
                vec![verdict("gpu", true, &[])],
            ),
        )
        .unwrap()
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
        let c = choose_among(
            &FORMS,
            " under WebGPU's default limits",
            lister(
                vec![verdict("gpu", true, &["9 storage buffers per stage"])],
                vec![verdict("gpu", true, &[])],
            ),
        )
        .unwrap()
        .0;
        assert!(c.pipeline.ends_with("pipelines/ssbvb.ron"), "{c:?}");
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
        let c = choose_among(
            &FORMS,
            "",
            lister(
                vec![verdict("gpu", true, &["x"]), verdict("cpu", true, &[])],
                vec![verdict("gpu", true, &[]), verdict("cpu", true, &[])],
            ),
        )
        .unwrap()
        .0;
        assert!(c.pipeline.ends_with("pipelines/ssbvb.ron"), "{c:?}");
        assert_eq!(c.adapter.as_deref(), Some("gpu [Vulkan, DiscreteGpu]"));
    }

    #[test]
    fn adapters_not_allowed_are_passed_over_and_none_fitting_says_so() {
        let (c, picked) = choose_among(
            &FORMS,
            "",
            lister(
                vec![verdict("gpu", false, &[]), verdict("cpu", true, &[])],
                vec![verdict("gpu", false, &[]), verdict("cpu", true, &[])],
            ),
        )
        .unwrap();
        assert_eq!(
            picked.map(|(a, v)| (a, v.name)),
            Some((1, "cpu".to_string()))
        );
        assert!(c.pipeline.ends_with("ssbvb_pixel.ron"), "{c:?}");
        assert!(c.reason.contains("on cpu"), "{c:?}");
        let (none, picked) = choose_among(
            &FORMS,
            "",
            lister(
                vec![verdict("gpu", true, &["a"])],
                vec![verdict("gpu", true, &["b"])],
            ),
        )
        .unwrap();
        assert!(none.pipeline.ends_with("pipelines/ssbvb.ron"), "{none:?}");
        assert!(none.reason.contains("no adapter fits"), "{none:?}");
        assert_eq!(none.adapter, None);
        assert!(picked.is_none());
    }

    #[test]
    fn a_flag_or_a_scene_wins_over_the_rule() {
        let c = choose(Some("a.ron".into()), Some("b.ron".into())).unwrap();
        assert_eq!((c.pipeline.as_str(), c.by), ("a.ron", "flag"));
        let c = choose(None, Some("b.ron".into())).unwrap();
        assert_eq!((c.pipeline.as_str(), c.by), ("b.ron", "scene"));
    }
}

#[cfg(test)]
mod web_page_tests {
    /// The web page chooses its default among the same forms, in the same order, with the
    /// same ones kept for CPU adapters (a browser's fallback adapter).
    #[test]
    fn the_page_chooses_among_the_same_forms() {
        let stem = |f: &super::Form| {
            f.file
                .trim_start_matches("pipelines/")
                .trim_end_matches(".ron")
                .to_string()
        };
        let stems: Vec<String> = super::FORMS.iter().map(stem).collect();
        assert_eq!(stems, ssbvb_web::params::DEFAULT_FORMS);
        let cpu_only: Vec<String> = super::FORMS
            .iter()
            .filter(|f| f.cpu_only)
            .map(stem)
            .collect();
        assert_eq!(cpu_only, ssbvb_web::params::CPU_ONLY_FORMS);
    }
}
