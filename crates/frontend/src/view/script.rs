//! The viewer's automation: brush steps (`--paint`: clicks at window pixels, undo, redo
//! and save, applied in order after the first frame), a turning camera (`--orbit`) and the
//! last camera as `render` flags.

use ssbvb_voxel::camera::Camera;

use super::brush_history::Step;

/// One step of `--paint`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScriptStep {
    /// Apply the brush at a window pixel.
    Paint(u32, u32),
    /// Undo or redo.
    Step(Step),
    /// Save to the save path.
    Save,
}

/// `X,Y`, `undo`, `redo` or `save`.
pub fn parse_script_step(s: &str) -> Result<ScriptStep, String> {
    match s {
        "undo" => Ok(ScriptStep::Step(Step::Undo)),
        "redo" => Ok(ScriptStep::Step(Step::Redo)),
        "save" => Ok(ScriptStep::Save),
        _ => parse_pixel(s).map(|(x, y)| ScriptStep::Paint(x, y)),
    }
}

/// A window pixel `X,Y`.
fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("expected X,Y, got `{s}`"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|e| format!("bad pixel `{s}`: {e}"))
    };
    Ok((p(x)?, p(y)?))
}

/// Degrees the orbit camera turns a frame (`--orbit`): finite, at most half a turn either way.
pub fn parse_orbit(s: &str) -> Result<f64, String> {
    let deg: f64 = s
        .trim()
        .parse()
        .map_err(|e| format!("bad angle `{s}`: {e}"))?;
    if deg.is_finite() && deg.abs() <= 180.0 {
        Ok(deg)
    } else {
        Err(format!("expected degrees in [-180, 180], got `{s}`"))
    }
}

/// `camera` as the flags of `ssbvb render` that draw the same view (every number in its
/// shortest form that reads back exactly).
pub fn render_flags(camera: &Camera) -> String {
    let v = |v: glam::DVec3| format!("{},{},{}", v.x, v.y, v.z);
    // `--far 0`: none (the infinite projection).
    let far = if camera.far.is_finite() {
        camera.far
    } else {
        0.0
    };
    format!(
        "--camera-pos {} --look-at {} --up {} --fov-y {} --near {} --far {far}",
        v(camera.position),
        v(camera.look_at),
        v(camera.up),
        camera.fov_y_deg,
        camera.near
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbit_angles_are_finite_and_at_most_half_a_turn() {
        assert_eq!(parse_orbit("2.5"), Ok(2.5));
        assert_eq!(parse_orbit("-180"), Ok(-180.0));
        for bad in ["inf", "NaN", "181", "x", ""] {
            assert!(parse_orbit(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn render_flags_read_back_to_the_same_camera() {
        let camera = Camera {
            position: glam::DVec3::new(0.1, -2.0, 1.0 / 3.0),
            far: 50.0,
            ..Camera::default()
        };
        let flags = render_flags(&camera);
        let value = |name: &str| {
            let mut words = flags.split(' ');
            words
                .find(|w| *w == name)
                .and_then(|_| words.next())
                .unwrap()
        };
        let pos = crate::cli_values::parse_vec3(value("--camera-pos")).unwrap();
        assert_eq!(pos, camera.position);
        assert_eq!(value("--far"), "50");
        let infinite = Camera {
            far: f64::INFINITY,
            ..camera
        };
        assert!(render_flags(&infinite).ends_with("--far 0"));
    }
}
