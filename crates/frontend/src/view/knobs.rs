//! Pass parameters ("knobs") as generic fields, so the overlay can edit any pass kind,
//! including kinds added after this was written: a kind is turned into its serde form
//! (`{"RayMarchFilter": {"max_steps": 1024}}`), its fields are edited as numbers, booleans
//! or enum names, and the edited form is parsed back into a [`PassKind`], which
//! `ResolvedPipeline::with_pass_kind` puts in the pipeline (parameters never change a kind's
//! slots, so nothing is resolved again).

use serde_json::{Map, Value};
use ssbvb_graph::PassKind;

/// A kind's name and its parameter fields (empty for kinds without parameters).
pub fn fields(kind: &PassKind) -> (String, Map<String, Value>) {
    match serde_json::to_value(kind) {
        Ok(Value::String(name)) => (name, Map::new()),
        Ok(Value::Object(m)) if m.len() == 1 => {
            let (name, inner) = m.into_iter().next().expect("one entry");
            match inner {
                Value::Object(fields) => (name, fields),
                // Tuple or newtype variants have no named fields to edit.
                _ => (name, Map::new()),
            }
        }
        _ => (kind.name().to_string(), Map::new()),
    }
}

/// The kind named `name` with `fields`; `Err` with serde's message when a value does not
/// fit (for example a negative step count).
pub fn with_fields(name: &str, fields: Map<String, Value>) -> Result<PassKind, String> {
    if fields.is_empty() {
        // Kinds without parameters are unit variants: just the name.
        if let Ok(k) = serde_json::from_value(Value::String(name.to_string())) {
            return Ok(k);
        }
    }
    let mut outer = Map::new();
    outer.insert(name.to_string(), Value::Object(fields));
    serde_json::from_value(Value::Object(outer)).map_err(|e| e.to_string())
}

/// The names an enum-valued field accepts, found by asking serde with a name no enum has:
/// its "unknown variant `…`, expected `A` or `B`" message lists them; those the kind's
/// parameter check refuses (rasterized billboards in `Pixel` mode) are left out. Empty when
/// the field is not an enum.
pub fn enum_choices(name: &str, fields: &Map<String, Value>, field: &str) -> Vec<String> {
    const PROBE: &str = "\u{1}probe";
    let mut probe = fields.clone();
    probe.insert(field.to_string(), Value::String(PROBE.into()));
    let Err(msg) = with_fields(name, probe) else {
        return Vec::new();
    };
    let Some(expected) = msg.split("expected").nth(1) else {
        return Vec::new();
    };
    expected
        .split('`')
        .skip(1)
        .step_by(2)
        .filter(|choice| {
            let mut f = fields.clone();
            f.insert(field.to_string(), Value::String(choice.to_string()));
            with_fields(name, f).is_ok_and(|k| k.parameter_problems().is_empty())
        })
        .map(str::to_string)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use ssbvb_graph::BillboardMode;

    #[test]
    fn fields_round_trip_for_every_kind() {
        for kind in PassKind::all_defaults() {
            let (name, f) = fields(&kind);
            assert_eq!(name, kind.name());
            assert_eq!(with_fields(&name, f).as_ref(), Ok(&kind), "{name}");
        }
    }

    #[test]
    fn numbers_are_edited_and_bad_values_rejected() {
        let (name, mut f) = fields(&PassKind::RayMarchFilter(
            ssbvb_graph::RayMarchFilterParams {
                max_steps: 1024,
                unique_voxels: false,
                ..Default::default()
            },
        ));
        f.insert("max_steps".into(), Value::from(64));
        assert_eq!(
            with_fields(&name, f.clone()),
            Ok(PassKind::RayMarchFilter(
                ssbvb_graph::RayMarchFilterParams {
                    max_steps: 64,
                    unique_voxels: false,
                    ..Default::default()
                }
            ))
        );
        f.insert("max_steps".into(), Value::from(-1));
        assert!(with_fields(&name, f).is_err());
    }

    #[test]
    fn enum_fields_list_their_choices() {
        let kind = PassKind::Billboards(ssbvb_graph::BillboardsParams {
            mode: BillboardMode::Flat,
            size_scale: 1.0,
        });
        let (name, f) = fields(&kind);
        assert_eq!(enum_choices(&name, &f, "mode"), vec!["Flat", "RayBox"]);
        assert!(enum_choices(&name, &f, "size_scale").is_empty());
        // The compute splat has the Pixel mode the rasterized billboards refuse.
        let (name, f) = fields(&PassKind::SplatBillboards(Default::default()));
        assert_eq!(
            enum_choices(&name, &f, "mode"),
            vec!["Flat", "RayBox", "Pixel"]
        );
    }
}
