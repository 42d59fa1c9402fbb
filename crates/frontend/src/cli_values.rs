//! Values of command-line flags that several commands share.

use glam::DVec3;

pub(crate) use ssbvb_engine::values::parse_samples;

/// Parses `x,y,z`.
pub fn parse_vec3(s: &str) -> Result<DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| {
            p.trim()
                .parse::<f64>()
                .map_err(|e| format!("bad number `{p}` in `{s}`: {e}"))
        })
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(DVec3::new(x, y, z)),
        _ => Err(format!("expected three finite numbers x,y,z, got `{s}`")),
    }
}

/// How rays find the instances they may meet (`--instance-walk`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum InstanceWalk {
    /// The list of the ray's screen tile, nearest box first.
    #[default]
    Lists,
    /// The hierarchy over every visible instance's box.
    Hierarchy,
}
