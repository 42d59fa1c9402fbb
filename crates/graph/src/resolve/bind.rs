//! Phase 2 of resolution: binding. Each pass's `reads` and `writes` are matched against
//! the slots its kind declares; the bound resource must exist and fit the slot (class,
//! texture format, buffer layout), every slot must be bound once, and a pass's attachments
//! must share one size. Only the bindings that pass these checks reach the DAG.

use std::collections::{BTreeSet, HashMap};

use super::ctx::Ctx;
use crate::error::{GraphError, Loc, suggest};
use crate::format::Format;
use crate::kinds::{Access, SlotDesc};
use crate::schema::{Binding, PassDesc, ResourceDesc, SizeDesc};

/// A validated binding, before pruning: slot and resource declaration index.
#[derive(Clone)]
pub(super) struct RawBinding {
    pub(super) slot: SlotDesc,
    pub(super) resource: usize,
}

impl Ctx<'_> {
    /// The valid bindings of every pass, by pass index.
    pub(super) fn bind(&mut self, res_index: &HashMap<&str, usize>) -> Vec<Vec<RawBinding>> {
        let desc = self.desc;
        desc.passes
            .iter()
            .map(|p| self.check_bindings(p, res_index))
            .collect()
    }

    /// Checks one pass's bindings against its kind's slots; returns the valid ones.
    fn check_bindings(
        &mut self,
        p: &PassDesc,
        res_index: &HashMap<&str, usize>,
    ) -> Vec<RawBinding> {
        let desc = self.desc;
        let slots = p.kind.slots();
        let kind = p.kind.name().to_string();
        let mut out: Vec<RawBinding> = Vec::new();
        let mut attachments: Vec<(String, SizeDesc)> = Vec::new();
        for (access, list, word) in [
            (Access::Read, &p.reads, "reads"),
            (Access::Write, &p.writes, "writes"),
        ] {
            let mut seen = BTreeSet::new();
            for b in &list.0 {
                let at = self.at(self.loc.in_pass(&p.name, &b.resource));
                let Some(slot) = slots
                    .iter()
                    .find(|s| s.name == b.slot && s.access == access)
                else {
                    let expected: Vec<_> = slots
                        .iter()
                        .filter(|s| s.access == access)
                        .map(|s| format!("`{}`", s.name))
                        .collect();
                    let expected = if expected.is_empty() {
                        "none".to_string()
                    } else {
                        expected.join(", ")
                    };
                    self.errors.push(GraphError::UnknownSlot {
                        at: self.at(self.loc.in_pass(&p.name, &b.slot)),
                        pass: p.name.clone(),
                        kind: kind.clone(),
                        slot: b.slot.clone(),
                        access: word,
                        expected,
                    });
                    continue;
                };
                if !seen.insert(b.slot.clone()) {
                    self.errors.push(GraphError::DuplicateSlot {
                        at,
                        pass: p.name.clone(),
                        kind: kind.clone(),
                        slot: b.slot.clone(),
                    });
                    continue;
                }
                let Some(&ri) = res_index.get(b.resource.as_str()) else {
                    self.errors.push(GraphError::UnknownResource {
                        at,
                        pass: p.name.clone(),
                        resource: b.resource.clone(),
                        hint: suggest(
                            &b.resource,
                            desc.resources.0.iter().map(|(n, _)| n.as_str()),
                        ),
                    });
                    continue;
                };
                let r = &desc.resources.0[ri].1;
                if self.fits_slot(p, slot, b, r, at, &mut attachments) {
                    out.push(RawBinding {
                        slot: *slot,
                        resource: ri,
                    });
                }
            }
        }
        self.check_all_bound(p, &kind);
        if let Some((first, fs)) = attachments.first() {
            for (name, s) in &attachments[1..] {
                if s != fs {
                    self.errors.push(GraphError::AttachmentSizeMismatch {
                        at: self.at(self.loc.in_pass(&p.name, name)),
                        pass: p.name.clone(),
                        first: first.clone(),
                        first_size: format!("{fs:?}"),
                        second: name.clone(),
                        second_size: format!("{s:?}"),
                    });
                }
            }
        }
        out
    }

    /// Whether resource `r`, bound by `b`, fits `slot`'s class and format or layout
    /// (recording why not); texture attachments are collected for the size check.
    fn fits_slot(
        &mut self,
        p: &PassDesc,
        slot: &SlotDesc,
        b: &Binding,
        r: &ResourceDesc,
        at: Loc,
        attachments: &mut Vec<(String, SizeDesc)>,
    ) -> bool {
        match (r, slot.class) {
            (ResourceDesc::Texture { format, size }, c) if c.is_texture() => {
                if c.is_attachment() {
                    attachments.push((b.resource.clone(), *size));
                }
                if !c.formats().contains(format) {
                    self.errors.push(GraphError::FormatMismatch {
                        at,
                        pass: p.name.clone(),
                        slot: slot.name.to_string(),
                        resource: b.resource.clone(),
                        found: format!("{format:?}"),
                        accepted: fmt_formats(c.formats()),
                    });
                    false
                } else {
                    true
                }
            }
            (ResourceDesc::Buffer { layout, .. }, c) if !c.is_texture() => {
                let want = c.layout().unwrap_or(*layout);
                if want != *layout {
                    self.errors.push(GraphError::LayoutMismatch {
                        at,
                        pass: p.name.clone(),
                        slot: slot.name.to_string(),
                        resource: b.resource.clone(),
                        found: format!("{layout:?}"),
                        expected: format!("{want:?}"),
                    });
                    false
                } else {
                    true
                }
            }
            (r, c) => {
                self.errors.push(GraphError::ClassMismatch {
                    at,
                    pass: p.name.clone(),
                    slot: slot.name.to_string(),
                    resource: b.resource.clone(),
                    expected: c.describe(),
                    found: match r {
                        ResourceDesc::Texture { .. } => "texture",
                        ResourceDesc::Buffer { .. } => "buffer",
                    },
                });
                false
            }
        }
    }

    /// Records every slot of `p`'s kind that `p` does not bind.
    fn check_all_bound(&mut self, p: &PassDesc, kind: &str) {
        for s in p.kind.slots() {
            let bound = match s.access {
                Access::Read => p.reads.0.iter().any(|b| b.slot == s.name),
                Access::Write => p.writes.0.iter().any(|b| b.slot == s.name),
            };
            if !bound {
                self.errors.push(GraphError::MissingSlot {
                    at: self.at(self.loc.pass(&p.name)),
                    pass: p.name.clone(),
                    kind: kind.to_string(),
                    slot: s.name.to_string(),
                    access: if s.access == Access::Read {
                        "read"
                    } else {
                        "write"
                    },
                    class: s.class.describe(),
                });
            }
        }
    }
}

fn fmt_formats(f: &[Format]) -> String {
    f.iter()
        .map(|f| format!("{f:?}"))
        .collect::<Vec<_>>()
        .join(" | ")
}
