//! Phase 1 of resolution: the declarations. Every resource and pass name must be unique,
//! resource sizes and counts must be in range and every pass's parameters must make sense
//! for its kind. The name indices built here are what the later phases look names up in.

use std::collections::HashMap;

use super::ctx::Ctx;
use super::resolved::{MAX_BUFFER_ELEMENTS, MAX_TEXTURE_EDGE};
use crate::error::GraphError;
use crate::format::BufferLayout;
use crate::schema::{CountDesc, ResourceDesc, SizeDesc};

/// Declaration indices by name (the first declaration wins on duplicates).
pub(super) struct Declared<'a> {
    /// Resource name → index in `desc.resources`.
    pub(super) resources: HashMap<&'a str, usize>,
    /// Pass name → index in `desc.passes`.
    pub(super) passes: HashMap<&'a str, usize>,
}

impl<'a> Ctx<'a> {
    /// Checks the resource and pass declarations and indexes them by name.
    pub(super) fn declare(&mut self) -> Declared<'a> {
        let resources = self.declare_resources();
        let passes = self.declare_passes();
        Declared { resources, passes }
    }

    /// Duplicate resource names and out-of-range sizes or counts.
    fn declare_resources(&mut self) -> HashMap<&'a str, usize> {
        let desc = self.desc;
        let mut res_index: HashMap<&str, usize> = HashMap::new();
        for (i, (name, r)) in desc.resources.0.iter().enumerate() {
            if res_index.insert(name.as_str(), i).is_some() {
                let nth = desc.resources.0[..i]
                    .iter()
                    .filter(|(n, _)| n == name)
                    .count();
                self.errors.push(GraphError::DuplicateResource {
                    at: self.at(self.loc.resource_declarations(name).get(nth).copied()),
                    resource: name.clone(),
                });
            }
            if let Some(message) = resource_problem(r) {
                self.errors.push(GraphError::BadResource {
                    at: self.at(self.loc.resource(name)),
                    resource: name.clone(),
                    message,
                });
            }
        }
        res_index
    }

    /// Duplicate pass names and parameters the pass's kind rejects.
    fn declare_passes(&mut self) -> HashMap<&'a str, usize> {
        let desc = self.desc;
        let mut pass_index: HashMap<&str, usize> = HashMap::new();
        for (i, p) in desc.passes.iter().enumerate() {
            if pass_index.insert(p.name.as_str(), i).is_some() {
                let nth = desc.passes[..i].iter().filter(|q| q.name == p.name).count();
                let at = self.at(self.loc.pass_declarations(&p.name).get(nth).copied());
                self.errors.push(GraphError::DuplicatePass {
                    at,
                    pass: p.name.clone(),
                });
            }
            for message in p.kind.parameter_problems() {
                self.errors.push(GraphError::BadParameter {
                    at: self.at(self.loc.pass_field(&p.name, "kind")),
                    pass: p.name.clone(),
                    kind: p.kind.name().to_string(),
                    message,
                });
            }
        }
        pass_index
    }
}

/// What is wrong with a resource's size or count, if anything.
fn resource_problem(r: &ResourceDesc) -> Option<String> {
    match r {
        ResourceDesc::Texture { size, .. } => match *size {
            SizeDesc::ScreenScaled(f) if !(f.is_finite() && f > 0.0 && f <= 16.0) => {
                Some(format!("ScreenScaled factor must be in (0, 16], got {f}"))
            }
            SizeDesc::Fixed(w, h)
                if w == 0 || h == 0 || w > MAX_TEXTURE_EDGE || h > MAX_TEXTURE_EDGE =>
            {
                Some(format!(
                    "Fixed size must be 1..={MAX_TEXTURE_EDGE} texels per side, got {w}x{h}"
                ))
            }
            _ => None,
        },
        ResourceDesc::Buffer { count, layout } => match *count {
            CountDesc::ScreenPixelsScaled(f) if !(f.is_finite() && f > 0.0 && f <= 16.0) => Some(
                format!("ScreenPixelsScaled factor must be in (0, 16], got {f}"),
            ),
            CountDesc::Fixed(n) if n == 0 || n > MAX_BUFFER_ELEMENTS => Some(format!(
                "Fixed count must be 1..={MAX_BUFFER_ELEMENTS}, got {n}"
            )),
            CountDesc::Fixed(n) if *layout == BufferLayout::DrawIndirect && n != 1 => Some(
                format!("a DrawIndirect buffer holds one draw, got count {n}"),
            ),
            _ => None,
        },
    }
}
