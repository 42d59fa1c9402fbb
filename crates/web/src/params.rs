//! The page's URL parameters (`?scene=…&pipeline=…&size=WxH`), checked before anything is
//! fetched: a name is a bundled file's stem, a size is `WxH` within what a frame may be.

use crate::WebError;

/// The bundled scenes the page offers (file stems under `assets/scenes/`).
pub const SCENES: &[&str] = &["default", "bunnies_64", "bunnies_4096"];

/// The ray casters the page offers besides the SSBVB forms (file stems under
/// `assets/pipelines/`).
pub const RAY_CASTERS: &[&str] = &["esvo", "octree"];

/// The bundled pipelines the page offers (file stems under `assets/pipelines/`): the SSBVB
/// forms of the engine's table ([`ssbvb_engine::FORMS`]), then the ray casters.
pub fn pipelines() -> Vec<&'static str> {
    ssbvb_engine::FORMS
        .iter()
        .map(|f| f.stem())
        .chain(RAY_CASTERS.iter().copied())
        .collect()
}

/// The largest frame edge the page renders at (WebGPU's default texture limit is 8192).
pub const MAX_EDGE: u32 = 4096;

/// What the page draws.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PageParams {
    /// A bundled scene's stem.
    pub scene: String,
    /// A bundled pipeline's stem; `None`: the default SSBVB form for the adapter.
    pub pipeline: Option<String>,
    /// Render size; `None`: the canvas's size.
    pub size: Option<(u32, u32)>,
}

impl PageParams {
    /// Reads `(key, value)` pairs of a query string; unknown keys are ignored (a page link
    /// may carry others), bad values are errors naming the parameter.
    pub fn parse<'a>(
        pairs: impl IntoIterator<Item = (&'a str, &'a str)>,
    ) -> Result<Self, WebError> {
        let mut p = PageParams {
            scene: "default".into(),
            pipeline: None,
            size: None,
        };
        for (key, value) in pairs {
            match key {
                "scene" => p.scene = one_of("scene", value, SCENES)?,
                "pipeline" => {
                    p.pipeline = Some(one_of("pipeline", current_stem(value), &pipelines())?)
                }
                "size" => p.size = Some(parse_size(value)?),
                _ => {}
            }
        }
        Ok(p)
    }
}

/// A pipeline's stem, or the new stem of a renamed bundled file's old one
/// ([`ssbvb_graph::RENAMED_FILES`]).
fn current_stem(stem: &str) -> &str {
    ssbvb_graph::RENAMED_FILES
        .iter()
        .find(|(old, _)| old.strip_suffix(".ron") == Some(stem))
        .and_then(|(_, new)| new.strip_suffix(".ron"))
        .unwrap_or(stem)
}

fn one_of(key: &str, value: &str, names: &[&str]) -> Result<String, WebError> {
    if names.contains(&value) {
        Ok(value.to_string())
    } else {
        Err(WebError::Param {
            key: key.into(),
            message: format!("`{value}` is not one of {}", names.join(", ")),
        })
    }
}

/// `WxH`, each in `1..=MAX_EDGE`.
pub fn parse_size(value: &str) -> Result<(u32, u32), WebError> {
    let bad = |message: String| WebError::Param {
        key: "size".into(),
        message,
    };
    let (w, h) = value
        .split_once(['x', 'X'])
        .ok_or_else(|| bad(format!("`{value}` is not WxH (e.g. 320x240)")))?;
    let edge = |s: &str| -> Result<u32, WebError> {
        match s.trim().parse::<u32>() {
            Ok(n) if (1..=MAX_EDGE).contains(&n) => Ok(n),
            _ => Err(bad(format!(
                "`{value}`: each side must be a whole number in 1..={MAX_EDGE}"
            ))),
        }
    };
    Ok((edge(w)?, edge(h)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_values_are_read() {
        let p = PageParams::parse([]).unwrap();
        assert_eq!(p.scene, "default");
        assert_eq!(p.pipeline, None);
        assert_eq!(p.size, None);
        let p = PageParams::parse([
            ("scene", "bunnies_64"),
            ("pipeline", "esvo"),
            ("size", "320x240"),
            ("utm", "x"),
        ])
        .unwrap();
        assert_eq!(p.scene, "bunnies_64");
        assert_eq!(p.pipeline.as_deref(), Some("esvo"));
        let old = PageParams::parse([("pipeline", "octree_ray_cast")]).unwrap();
        assert_eq!(old.pipeline.as_deref(), Some("octree"));
        assert_eq!(p.size, Some((320, 240)));
    }

    #[test]
    fn bad_values_name_their_parameter() {
        for (pairs, want) in [
            (
                vec![("scene", "../../etc/passwd")],
                "scene: `../../etc/passwd` is not one of",
            ),
            (vec![("pipeline", "nope")], "pipeline: `nope` is not one of"),
            (vec![("size", "320")], "size: `320` is not WxH"),
            (vec![("size", "0x240")], "size: `0x240`: each side"),
            (
                vec![("size", "5000x10")],
                "each side must be a whole number in 1..=4096",
            ),
            (vec![("size", "-3x10")], "each side"),
        ] {
            let e = PageParams::parse(pairs).unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
        }
    }

    /// Every name the page offers is a bundled file, and every form of the table is offered.
    #[test]
    fn every_offered_name_is_a_bundled_file() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        for s in SCENES {
            assert!(root.join(format!("scenes/{s}.ron")).is_file(), "{s}");
        }
        let offered = pipelines();
        for p in &offered {
            assert!(root.join(format!("pipelines/{p}.ron")).is_file(), "{p}");
        }
        for f in &ssbvb_engine::FORMS {
            assert!(offered.contains(&f.stem()), "{}", f.name);
        }
    }
}
