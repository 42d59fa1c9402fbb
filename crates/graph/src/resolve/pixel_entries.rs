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
