//! The viewer's automation steps (`--paint`): brush clicks at window pixels, undo, redo
//! and save, applied in order after the first frame.

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
