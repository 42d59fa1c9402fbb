//! Values of command-line flags that several commands share.

use glam::DVec3;

/// Parses a sample count of `--samples` (1 to 1024).
pub(crate) fn parse_samples(s: &str) -> Result<u32, String> {
    let n: u32 = s
        .trim()
        .parse()
        .map_err(|e| format!("bad sample count `{s}`: {e}"))?;
    ssbvb_voxel::reference::SampleGrid::from_count(n)
        .map(|g| g.count())
        .map_err(|e| e.to_string())
}

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
