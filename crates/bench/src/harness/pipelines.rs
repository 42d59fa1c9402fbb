//! The bundled pipelines and the edits the presets make to them.

use anyhow::{Result, bail};
use ssbvb_graph::{
    CountDesc, Format, PassKind, ResolvedPipeline, ResourceDesc, SizeDesc, SmoothComputeParams,
};

use super::techniques::{PipelineSource, Technique};
use ssbvb_engine::assets::assets_dir;

/// The bundled pipeline `file` (in `assets/pipelines`), resolved.
pub(crate) fn bundled_pipeline(file: &str) -> Result<ResolvedPipeline> {
    let path = assets_dir().join("pipelines").join(file);
    ssbvb_graph::resolve_file(&path).map_err(|e| anyhow::anyhow!("{e}"))
}

/// `base` with `edit` applied to its pass kinds; an error when `edit` changes none (the
/// pipeline lacks the kind it edits) or the edited pipeline does not resolve.
pub(crate) fn with_kind_edit(
    base: &ResolvedPipeline,
    what: &str,
    edit: impl FnMut(&mut PassKind) -> bool,
) -> Result<ResolvedPipeline> {
    let mut changed = 0;
    let p = base
        .edited(|d| changed = d.edit_kinds(edit))
        .map_err(|e| anyhow::anyhow!("{what}: {e}"))?;
    if changed == 0 {
        bail!("{what}: {} has no pass of the kind this edits", base.file);
    }
    Ok(p)
}

/// The pipeline of technique `t`: its bundled file (or the adapter's default SSBVB form)
/// with its edit, if any.
pub(crate) fn technique_pipeline(t: &Technique) -> Result<ResolvedPipeline> {
    let p = match t.pipeline {
        PipelineSource::File(f) => bundled_pipeline(f)?,
        PipelineSource::Form(name) => {
            let Some(form) = ssbvb_engine::forms::by_name(name) else {
                bail!(
                    "technique `{}`: no form `{name}` in the engine's table",
                    t.name
                );
            };
            crate::harness::engine::resolve(&assets_dir().join(form.file))?
        }
        PipelineSource::SharedStagesInCompute(f) => {
            with_shared_stages_in_compute(&bundled_pipeline(f)?)?
        }
        PipelineSource::AdapterDefault => {
            let choice = crate::harness::engine::default_form()?;
            log::info!("bench: technique `{}`: {}", t.name, choice.line());
            crate::harness::engine::resolve(&choice.path())?
        }
    };
    match t.edit {
        Some(e) => with_kind_edit(&p, t.name, e),
        None => Ok(p),
    }
}

/// `base` with the stages every technique shares in compute: `Smooth` made
/// `SmoothCompute` with its parameters, `Composite` made `CompositeCompute`, and the
/// output made `Rgba8Unorm` (a storage texture, sRGB-encoded by the composite). The same
/// image (GPU test `smooth_composite`); a bench pair that compares two frames edits both.
pub(crate) fn with_shared_stages_in_compute(base: &ResolvedPipeline) -> Result<ResolvedPipeline> {
    let mut swapped = 0;
    let p = base
        .edited(|d| {
            swapped = d.edit_kinds(|k| match k {
                PassKind::Smooth(s) => {
                    *k = PassKind::SmoothCompute(SmoothComputeParams {
                        max_i: s.max_i,
                        min_dist: s.min_dist,
                    });
                    true
                }
                PassKind::Composite => {
                    *k = PassKind::CompositeCompute;
                    true
                }
                _ => false,
            });
            if let Some(ResourceDesc::Texture { format, .. }) = d.resource_mut("color") {
                *format = Format::Rgba8Unorm;
            }
        })
        .map_err(|e| anyhow::anyhow!("{} with its shared stages in compute: {e}", base.file))?;
    if swapped != 2 {
        bail!(
            "{}: not one Smooth and one Composite to make compute",
            base.file
        );
    }
    Ok(p)
}

/// The default SSBVB pipeline with the empty-space prepass and the ray-march filter at
/// `scale` of the screen per axis (their textures and the SSBVB shrink with it); the
/// billboards, smoothing and composite stay at full resolution.
pub(crate) fn with_filter_scale(base: &ResolvedPipeline, scale: f64) -> Result<ResolvedPipeline> {
    if scale == 1.0 {
        return Ok(base.clone());
    }
    let scale = scale as f32;
    base.edited(|d| {
        for r in ["entry", "prepass_depth"] {
            if let Some(ResourceDesc::Texture { size, .. }) = d.resource_mut(r) {
                *size = SizeDesc::ScreenScaled(scale);
            }
        }
        if let Some(ResourceDesc::Buffer { count, .. }) = d.resource_mut("ssbvb") {
            *count = CountDesc::ScreenPixelsScaled(scale);
        }
    })
    .map_err(|e| anyhow::anyhow!("resolution scale {scale}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_edits_need_a_pass_of_the_kind() {
        let base = bundled_pipeline("dense_dda.ron").unwrap();
        let err = with_kind_edit(&base, "max_steps", |k| match k {
            PassKind::RayMarchFilter(f) => {
                f.max_steps = 3;
                true
            }
            _ => false,
        })
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("max_steps") && err.contains("dense_dda.ron"),
            "{err}"
        );
    }

    #[test]
    fn filter_scale_pipeline_resolves_with_scaled_resources() {
        let base = bundled_pipeline("ssbvb_flat.ron").unwrap();
        let p = with_filter_scale(&base, 0.5).unwrap();
        let entry = p.resource("entry").unwrap();
        match &p.resources[entry].desc {
            ssbvb_graph::ResourceDesc::Texture { size, .. } => {
                assert_eq!(size.resolve((640, 480)), (320, 240))
            }
            _ => panic!("entry is a texture"),
        }
    }
}
