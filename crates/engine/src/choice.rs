//! The pipeline of a render: the caller's, else the scene's, else the default form for the
//! adapter at hand: the form `ssbvb calibrate` measured fastest on this adapter, driver and
//! limits, else the rule of [`crate::forms`] over the forms of its table.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use ssbvb_gpu::{AdapterVerdict, DeviceLimits, GpuContext, Requirements};
use ssbvb_graph::ResolvedPipeline;

use crate::assets::assets_dir;
use crate::forms::{Form, PipelineChoice, choose_among, rule_forms};
use crate::{EngineError, Warning};

/// The limits a program's devices are made with when it does not say otherwise: set once
/// by a command line's `--limits` ([`set_process_limits`]).
static PROCESS_LIMITS: std::sync::OnceLock<DeviceLimits> = std::sync::OnceLock::new();

/// Sets the limits of this process's devices (the first call wins).
pub fn set_process_limits(limits: DeviceLimits) {
    let _ = PROCESS_LIMITS.set(limits);
}

/// The limits of this process's devices ([`DeviceLimits::Adapter`] unless set).
pub fn process_limits() -> DeviceLimits {
    PROCESS_LIMITS.get().copied().unwrap_or_default()
}

/// A headless device on the best adapter that runs every one of `pipelines`, under
/// [`process_limits`].
pub fn headless_context(pipelines: &[&ResolvedPipeline]) -> Result<GpuContext, EngineError> {
    Ok(GpuContext::new_headless(&ssbvb_gpu::ContextOptions {
        requirements: Some(requirements_of(pipelines)),
        limits: process_limits(),
        ..Default::default()
    })?)
}

/// Resolves a pipeline file; the error lists every problem of the file with its line.
pub fn resolve_pipeline(path: &Path) -> Result<ResolvedPipeline, EngineError> {
    ssbvb_graph::resolve_file(path).map_err(|e| EngineError::Pipeline(e.to_string()))
}

/// What `pipelines` together need from an adapter.
pub fn requirements_of(pipelines: &[&ResolvedPipeline]) -> Requirements {
    let mut req = Requirements::default();
    for p in pipelines {
        req.merge(&ssbvb_passes::pipeline_requirements(p));
    }
    req
}

/// The pipeline of a render: `named` (the caller's, `by: "flag"`), else the scene's, else
/// the default for the adapter under `limits`.
pub fn choose(
    named: Option<PathBuf>,
    scene: Option<PathBuf>,
    limits: DeviceLimits,
) -> Result<PipelineChoice, EngineError> {
    if let Some(p) = named {
        return Ok(PipelineChoice {
            pipeline: p.display().to_string(),
            by: "flag",
            reason: "named with --pipeline".into(),
            adapter: None,
            warnings: Vec::new(),
        });
    }
    if let Some(p) = scene {
        return Ok(PipelineChoice {
            pipeline: p.display().to_string(),
            by: "scene",
            reason: "named by the scene file's `pipeline:`".into(),
            adapter: None,
            warnings: Vec::new(),
        });
    }
    default_for_adapter(limits)
}

/// The default for the adapter under `limits` (made once per process and limits: the
/// adapters do not change under a running program): the form `ssbvb calibrate` measured
/// fastest on this adapter, driver and limits, else the rule's.
pub fn default_for_adapter(limits: DeviceLimits) -> Result<PipelineChoice, EngineError> {
    static CHOICES: Mutex<Vec<(DeviceLimits, PipelineChoice)>> = Mutex::new(Vec::new());
    let made = |l| {
        let found = CHOICES.lock().ok()?;
        found.iter().find(|(k, _)| *k == l).map(|(_, c)| c.clone())
    };
    if let Some(c) = made(limits) {
        return Ok(c);
    }
    let (rule, picked) = rule_choice(limits)?;
    let c = match picked {
        Some((a, adapter)) => calibrated(rule, a, &adapter, &crate::calibration::path(), limits)?,
        None => rule,
    };
    if let Ok(mut list) = CHOICES.lock() {
        list.push((limits, c.clone()));
    }
    Ok(c)
}

/// The rule's choice under `limits`, with the adapter it looked at.
fn rule_choice(
    limits: DeviceLimits,
) -> Result<(PipelineChoice, Option<(usize, AdapterVerdict)>), EngineError> {
    let forms = rule_forms();
    let requirements = forms
        .iter()
        .map(|f| {
            let pipeline = resolve_pipeline(&assets_dir().join(f.file))?;
            Ok(requirements_of(&[&pipeline]))
        })
        .collect::<Result<Vec<_>, EngineError>>()?;
    let per_form = GpuContext::list_adapters_for(&requirements, limits);
    Ok(choose_among(&forms, under(limits), &per_form, file_of))
}

/// A form's pipeline file as a choice names it.
fn file_of(f: &Form) -> String {
    assets_dir().join(f.file).display().to_string()
}

/// How a reason names the limits.
fn under(limits: DeviceLimits) -> &'static str {
    match limits {
        DeviceLimits::Adapter => "",
        DeviceLimits::WebGpuDefaults => " under WebGPU's default limits",
    }
}

/// `rule` unless the calibration file at `file` has an entry for `adapter` (the `a`th
/// listed) under `limits` whose fastest form the adapter fits. An unreadable calibration
/// is ignored with a warning (in the choice's warnings and its reason).
fn calibrated(
    mut rule: PipelineChoice,
    a: usize,
    adapter: &AdapterVerdict,
    file: &Path,
    limits: DeviceLimits,
) -> Result<PipelineChoice, EngineError> {
    let key = crate::calibration::AdapterKey::of(adapter, limits.name());
    let entry = match crate::calibration::load(file) {
        Ok(f) => f.and_then(|f| crate::calibration::lookup(&f, &key).cloned()),
        Err(e) => {
            let w = format!("the calibration was ignored ({e}); `ssbvb calibrate` measures again");
            rule.reason.push_str(&format!("; {w}"));
            rule.warnings
                .push(Warning::new(file.display().to_string(), w));
            None
        }
    };
    let Some((entry, fastest)) = entry.and_then(|e| Some((e.clone(), e.fastest()?.to_string())))
    else {
        return Ok(rule);
    };
    let pipeline = resolve_pipeline(&assets_dir().join(&fastest))?;
    let fits = GpuContext::list_adapters(&requirements_of(&[&pipeline]), limits)
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
            under(limits),
            entry.summary()
        ),
        adapter: rule.adapter,
        warnings: rule.warnings,
    })
}

/// The pipeline of a render on a host's device: `named`, else the scene's, else the
/// first form of the rule the host's adapter runs (the rule of [`default_for_adapter`] over
/// that one adapter; no calibration, which is of this process's own adapters).
pub fn choose_for_host(
    named: Option<PathBuf>,
    scene: Option<PathBuf>,
    host: &crate::HostDevice,
) -> Result<PipelineChoice, EngineError> {
    if named.is_some() || scene.is_some() {
        return choose(named, scene, DeviceLimits::Adapter);
    }
    let info = host.adapter.get_info();
    let forms = rule_forms();
    let per_form = forms
        .iter()
        .map(|f| {
            let pipeline = resolve_pipeline(&assets_dir().join(f.file))?;
            let verdict =
                requirements_of(&[&pipeline]).check_under(&host.adapter, &host.device.limits());
            Ok(vec![AdapterVerdict {
                name: info.name.clone(),
                backend: format!("{:?}", info.backend),
                device_type: format!("{:?}", info.device_type),
                driver: format!("{} {}", info.driver, info.driver_info),
                allowed: true,
                verdict,
            }])
        })
        .collect::<Result<Vec<_>, EngineError>>()?;
    Ok(choose_among(&forms, " (the host's device)", &per_form, file_of).0)
}

/// The adapter the rule picks under `limits` (the best allowed one that fits any of its
/// forms) and which of `files` (pipeline files relative to the assets folder) it fits, in
/// their order.
pub fn adapter_and_fitting_forms(
    files: &[&'static str],
    limits: DeviceLimits,
) -> Result<(AdapterVerdict, Vec<&'static str>), EngineError> {
    let (_, picked) = rule_choice(limits)?;
    let Some((a, adapter)) = picked else {
        return Err(EngineError::Invalid(format!(
            "no adapter fits any SSBVB form{}",
            under(limits)
        )));
    };
    let mut fitting = Vec::new();
    for f in files {
        let pipeline = resolve_pipeline(&assets_dir().join(f))?;
        if GpuContext::list_adapters(&requirements_of(&[&pipeline]), limits)
            .get(a)
            .is_some_and(|v| v.allowed && v.verdict.fits())
        {
            fitting.push(*f);
        }
    }
    Ok((adapter, fitting))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_name_or_a_scene_wins_over_the_rule() {
        let l = DeviceLimits::Adapter;
        let c = choose(Some("a.ron".into()), Some("b.ron".into()), l).unwrap();
        assert_eq!((c.pipeline.as_str(), c.by), ("a.ron", "flag"));
        let c = choose(None, Some("b.ron".into()), l).unwrap();
        assert_eq!((c.pipeline.as_str(), c.by), ("b.ron", "scene"));
    }
}
