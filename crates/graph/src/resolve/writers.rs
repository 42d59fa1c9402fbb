//! A check between passes, after the DAG: a kind may set a rule on the passes writing the
//! resource bound to one of its read slots ([`crate::PassKind::writers_rule`], declared
//! with the kind); each writer breaking it is an error at the reading pass's kind.

use super::bind::RawBinding;
use super::ctx::Ctx;
use super::dag::Dag;
use crate::error::GraphError;
use crate::kinds::Writer;
use crate::schema::{ResourceDesc, SizeDesc};

impl Ctx<'_> {
    /// Checks every pass's writers rule against the passes that write its slot.
    pub(super) fn check_writers_rules(&mut self, dag: &Dag, bindings: &[Vec<RawBinding>]) {
        let desc = self.desc;
        for (pi, p) in desc.passes.iter().enumerate() {
            let Some(rule) = p.kind.writers_rule() else {
                continue;
            };
            let Some(read) = bindings[pi].iter().find(|b| b.slot.name == rule.slot) else {
                continue;
            };
            for &w in dag.writers.get(read.resource).into_iter().flatten() {
                let writer = &desc.passes[w];
                let texture = |slot: &str| {
                    let b = bindings[w].iter().find(|b| b.slot.name == slot)?;
                    match &desc.resources.0[b.resource] {
                        (name, ResourceDesc::Texture { size, .. }) => {
                            Some((name.as_str(), size as &SizeDesc))
                        }
                        _ => None,
                    }
                };
                let seen = Writer {
                    kind: &writer.kind,
                    texture: &texture,
                };
                if let Some(problem) = (rule.check)(&seen) {
                    self.errors.push(GraphError::BadParameter {
                        at: self.at(self.loc.pass_field(&p.name, "kind")),
                        pass: p.name.clone(),
                        kind: p.kind.name().to_string(),
                        message: format!(
                            "{}, but the {} `{}` that writes `{}` {problem}",
                            rule.because, rule.role, writer.name, desc.resources.0[read.resource].0
                        ),
                    });
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{PipelineErrors, ResolvedPipeline, resolve_str};

    fn ok(src: &str) -> ResolvedPipeline {
        resolve_str(src, "test.ron").unwrap_or_else(|e| panic!("expected a pipeline:\n{e}"))
    }

    fn err(src: &str) -> PipelineErrors {
        match resolve_str(src, "test.ron") {
            Ok(_) => panic!("expected errors"),
            Err(e) => e,
        }
    }

    fn line_of(src: &str, needle: &str) -> usize {
        src.lines()
            .position(|l| l.contains(needle))
            .expect("needle")
            + 1
    }

    fn assert_mentions(e: &PipelineErrors, parts: &[&str]) {
        let text = e.to_string();
        for p in parts {
            assert!(text.contains(p), "{p:?} not in:\n{text}");
        }
    }

    /// `SplatBillboards(mode: Pixel)` draws each entry at its own pixel only: the filter that
    /// writes its SSBVB must append every pixel at the screen's resolution, and rasterized
    /// billboards have no Pixel mode. Each refusal names the pass, the filter and the line.
    #[test]
    fn pixel_entries_need_a_filter_that_appends_every_pixel_at_full_resolution() {
        let pixel = include_str!("../../../../assets/pipelines/ssbvb_pixel.ron");
        let p = ok(pixel);
        assert!(
            p.passes.iter().any(|s| matches!(
                &s.kind,
                crate::PassKind::SplatBillboards(b) if b.mode == crate::BillboardMode::Pixel
            )),
            "the bundled Pixel pipeline splats in Pixel mode"
        );
        let unique = pixel.replace("unique_voxels: false", "unique_voxels: true");
        assert_ne!(unique, pixel);
        let e = err(&unique);
        assert_mentions(
            &e,
            &[
                "pass `billboards`",
                "filter `filter`",
                "unique_voxels: true",
            ],
        );
        assert_eq!(e.errors.len(), 1, "{e}");
        assert_eq!(
            e.errors[0].loc().pos.map(|p| p.line),
            Some(line_of(&unique, "kind: SplatBillboards(mode: Pixel)"))
        );
        let scaled = pixel.replace(
            "\"entry\":            Texture(format: Rgba32Float, size: Screen)",
            "\"entry\":            Texture(format: Rgba32Float, size: ScreenScaled(0.5))",
        );
        assert_ne!(scaled, pixel);
        assert_mentions(
            &err(&scaled),
            &["`entry` texture `entry` is not of size Screen"],
        );
        let raster = pixel.replace("SplatBillboards(mode: Pixel)", "Billboards(mode: Pixel)");
        assert_mentions(
            &err(&raster),
            &["(Billboards): mode: Pixel", "SplatBillboards"],
        );
        // The other modes do not care how the filter appends.
        ok(&unique.replace(
            "SplatBillboards(mode: Pixel)",
            "SplatBillboards(mode: RayBox)",
        ));
    }
}
