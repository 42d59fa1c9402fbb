//! Rules a kind sets on the passes that write what it reads, checked once the graph is
//! built ([`PassKind::writers_rule`]): the resolver applies them without naming a kind.

use super::{BillboardMode, PassKind};
use crate::schema::SizeDesc;

/// A pass writing the resource a rule's slot reads, as the rule sees it.
pub struct Writer<'a> {
    /// Its kind with its parameters.
    pub kind: &'a PassKind,
    /// The texture bound to one of its slots, by slot name: the resource's name and size
    /// (`None`: the slot is unbound or not a texture).
    pub texture: &'a dyn Fn(&str) -> Option<(&'a str, &'a SizeDesc)>,
}

/// What a kind needs of the passes writing the resource bound to one of its read slots.
#[derive(Clone, Copy)]
pub struct WritersRule {
    /// The read slot.
    pub slot: &'static str,
    /// Why, said before a writer that breaks the rule.
    pub because: &'static str,
    /// What the writers it checks are (in the message: "the filter `x`").
    pub role: &'static str,
    /// What is wrong with a writer (`None`: nothing, or a writer the rule does not check).
    pub check: fn(&Writer<'_>) -> Option<String>,
}

impl PassKind {
    /// The rule this kind with these parameters sets on the writers of one of its read
    /// slots, if any.
    pub fn writers_rule(&self) -> Option<WritersRule> {
        match self {
            PassKind::SplatBillboards(s) if s.mode == BillboardMode::Pixel => Some(PIXEL_ENTRIES),
            _ => None,
        }
    }
}

/// `SplatBillboards(mode: Pixel)` draws each SSBVB entry at the one pixel whose ray found
/// it, so every pixel must have its own entry: the filter writing the SSBVB must append
/// every pixel (`unique_voxels: false`: with unique voxels only the pixel that claimed a
/// voxel would show it, the others would be holes), and at the screen's resolution (its
/// `entry` texture of size `Screen`: an entry's pixel index is one of the filter's texels).
const PIXEL_ENTRIES: WritersRule = WritersRule {
    slot: "ssbvb",
    because: "mode: Pixel draws each entry at its own pixel only",
    role: "filter",
    check: every_pixel_its_entry,
};

fn every_pixel_its_entry(w: &Writer<'_>) -> Option<String> {
    let PassKind::RayMarchFilter(f) = w.kind else {
        return None;
    };
    let why = if f.unique_voxels {
        "it appends each voxel once (unique_voxels: true); set unique_voxels: false so that \
         every pixel has its entry"
            .to_string()
    } else {
        match (w.texture)("entry") {
            Some((name, size)) if *size != SizeDesc::Screen => format!(
                "its `entry` texture `{name}` is not of size Screen (a Pixel entry's pixel is \
                 one of the filter's texels)"
            ),
            _ => return None,
        }
    };
    Some(format!("cannot give every pixel its entry: {why}"))
}
