//! A check between passes, after the DAG: a `SplatBillboards(mode: Pixel)` draws each SSBVB
//! entry at the one pixel whose ray found it, so every pixel must have its own entry. The
//! filter writing its SSBVB must therefore append every pixel (`unique_voxels: false`:
//! with unique voxels only the pixel that claimed a voxel would show it, the others would
//! be holes), and at the screen's resolution (its `entry` texture of size `Screen`: an
//! entry's pixel index is one of the filter's texels).

use super::bind::RawBinding;
use super::ctx::Ctx;
use super::dag::Dag;
use crate::error::GraphError;
use crate::kinds::{BillboardMode, PassKind};
use crate::schema::{ResourceDesc, SizeDesc};

impl Ctx<'_> {
    /// Checks every Pixel splat against the passes that write its SSBVB.
    pub(super) fn check_pixel_entries(&mut self, dag: &Dag, bindings: &[Vec<RawBinding>]) {
        let desc = self.desc;
        for (pi, p) in desc.passes.iter().enumerate() {
            let PassKind::SplatBillboards(s) = &p.kind else {
                continue;
            };
            if s.mode != BillboardMode::Pixel {
                continue;
            }
            let Some(ssbvb) = bindings[pi].iter().find(|b| b.slot.name == "ssbvb") else {
                continue;
            };
            for &w in dag.writers.get(ssbvb.resource).into_iter().flatten() {
                let writer = &desc.passes[w];
                let problem = match &writer.kind {
                    PassKind::RayMarchFilter(f) if f.unique_voxels => Some(
                        "it appends each voxel once (unique_voxels: true); set \
                         unique_voxels: false so that every pixel has its entry"
                            .to_string(),
                    ),
                    PassKind::RayMarchFilter(_) => self.scaled_entry(&bindings[w]),
                    _ => None,
                };
                if let Some(problem) = problem {
                    self.errors.push(GraphError::BadParameter {
                        at: self.at(self.loc.pass_field(&p.name, "kind")),
                        pass: p.name.clone(),
                        kind: p.kind.name().to_string(),
                        message: format!(
                            "mode: Pixel draws each entry at its own pixel only, but the \
                             filter `{}` that writes `{}` cannot give every pixel its entry: \
                             {problem}",
                            writer.name, desc.resources.0[ssbvb.resource].0
                        ),
                    });
                }
            }
        }
    }

    /// Why a filter with these bindings does not run at the screen's resolution, if it
    /// does not.
    fn scaled_entry(&self, filter: &[RawBinding]) -> Option<String> {
        let entry = filter.iter().find(|b| b.slot.name == "entry")?;
        let (name, desc) = &self.desc.resources.0[entry.resource];
        match desc {
            ResourceDesc::Texture {
                size: SizeDesc::Screen,
                ..
            } => None,
            _ => Some(format!(
                "its `entry` texture `{name}` is not of size Screen (a Pixel entry's pixel is \
                 one of the filter's texels)"
            )),
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
