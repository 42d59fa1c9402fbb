//! Typed edits of a pipeline: the bench's technique variants and knob sweeps and the
//! viewer's knob editors change pass parameters and resource sizes on the parsed
//! description, never by rewriting RON text.

use crate::error::PipelineErrors;
use crate::kinds::PassKind;
use crate::resolve::{ResolvedPipeline, resolve_desc};
use crate::schema::{PipelineDesc, ResourceDesc};

impl PipelineDesc {
    /// Calls `edit` on every pass's kind; `edit` returns whether it changed that kind.
    /// Returns how many kinds it changed.
    pub fn edit_kinds(&mut self, mut edit: impl FnMut(&mut PassKind) -> bool) -> usize {
        self.passes
            .iter_mut()
            .map(|p| edit(&mut p.kind))
            .filter(|&changed| changed)
            .count()
    }

    /// The declaration of resource `name`, to change its size, count or format.
    pub fn resource_mut(&mut self, name: &str) -> Option<&mut ResourceDesc> {
        self.resources
            .0
            .iter_mut()
            .find(|(n, _)| n == name)
            .map(|(_, r)| r)
    }
}

impl ResolvedPipeline {
    /// This pipeline's description changed by `edit`, validated and resolved again (the
    /// errors of an invalid edit name passes and resources, without lines).
    pub fn edited(
        &self,
        edit: impl FnOnce(&mut PipelineDesc),
    ) -> Result<ResolvedPipeline, PipelineErrors> {
        let mut desc = self.desc.clone();
        edit(&mut desc);
        resolve_desc(&desc, &self.file)
    }

    /// This pipeline with pass `pass` given `kind`, which must be the same kind with other
    /// parameters (parameters never change a kind's slots, so nothing is resolved again).
    /// `None` when there is no such pass, the kind differs, or the parameters are invalid.
    pub fn with_pass_kind(&self, pass: &str, kind: &PassKind) -> Option<ResolvedPipeline> {
        if !kind.parameter_problems().is_empty() {
            return None;
        }
        let mut p = self.clone();
        let scheduled = p.passes.iter_mut().find(|s| s.name == pass)?;
        if std::mem::discriminant(&scheduled.kind) != std::mem::discriminant(kind) {
            return None;
        }
        scheduled.kind = kind.clone();
        if let Some(d) = p.desc.passes.iter_mut().find(|d| d.name == pass) {
            d.kind = kind.clone();
        }
        Some(p)
    }
}

#[cfg(test)]
mod tests {
    use crate::kinds::{PassKind, RayMarchFilterParams};
    use crate::schema::{ResourceDesc, SizeDesc};

    const SSBVB: &str = include_str!("../../../assets/pipelines/ssbvb_unique.ron");

    fn filter(p: &crate::ResolvedPipeline) -> PassKind {
        p.passes
            .iter()
            .find(|s| s.name == "filter")
            .unwrap()
            .kind
            .clone()
    }

    #[test]
    fn kind_edits_re_resolve_and_report_what_changed() {
        let p = crate::resolve_str(SSBVB, "ssbvb_unique.ron").unwrap();
        let mut changed = 0;
        let q = p
            .edited(|d| {
                changed = d.edit_kinds(|k| match k {
                    PassKind::RayMarchFilter(f) => {
                        f.max_steps = 7;
                        true
                    }
                    _ => false,
                });
            })
            .unwrap();
        assert_eq!(changed, 1);
        assert_eq!(
            filter(&q),
            PassKind::RayMarchFilter(RayMarchFilterParams {
                max_steps: 7,
                unique_voxels: true,
                march: crate::MarchMode::Fast,
                peel: false,
            })
        );
        // An invalid edit is refused with the pass named.
        let err = p
            .edited(|d| {
                d.edit_kinds(|k| match k {
                    PassKind::RayMarchFilter(f) => {
                        f.max_steps = 0;
                        true
                    }
                    _ => false,
                });
            })
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("max_steps must be at least 1") && err.contains("filter"),
            "{err}"
        );
    }

    #[test]
    fn resource_edits_change_sizes() {
        let p = crate::resolve_str(SSBVB, "ssbvb_unique.ron").unwrap();
        let scale = |d: &mut crate::PipelineDesc, names: &[&str]| {
            for n in names {
                if let Some(ResourceDesc::Texture { size, .. }) = d.resource_mut(n) {
                    *size = SizeDesc::ScreenScaled(0.5);
                }
            }
        };
        // The prepass's two attachments must keep one size.
        let err = p.edited(|d| scale(d, &["entry"])).unwrap_err().to_string();
        assert!(
            err.contains("entry") && err.contains("prepass_depth"),
            "{err}"
        );
        let q = p.edited(|d| scale(d, &["entry", "prepass_depth"])).unwrap();
        let e = q.resource("entry").unwrap();
        assert_eq!(
            q.resources[e].desc,
            ResourceDesc::Texture {
                format: crate::Format::Rgba32Float,
                size: SizeDesc::ScreenScaled(0.5)
            }
        );
        assert!(p.edited(|d| d.passes.clear()).is_err());
    }

    #[test]
    fn pass_kind_swaps_keep_the_variant() {
        let p = crate::resolve_str(SSBVB, "ssbvb_unique.ron").unwrap();
        let k = PassKind::RayMarchFilter(RayMarchFilterParams {
            max_steps: 9,
            unique_voxels: true,
            ..Default::default()
        });
        let q = p.with_pass_kind("filter", &k).unwrap();
        assert_eq!(filter(&q), k);
        assert!(p.with_pass_kind("filter", &PassKind::Composite).is_none());
        assert!(p.with_pass_kind("nope", &k).is_none());
        let bad = PassKind::RayMarchFilter(RayMarchFilterParams {
            max_steps: 0,
            unique_voxels: false,
            ..Default::default()
        });
        assert!(p.with_pass_kind("filter", &bad).is_none());
    }
}
