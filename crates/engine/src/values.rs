//! Values given as text on a command line or in a program's options, parsed once for every
//! front end: an image size, samples per pixel of the reference, device limits.

use ssbvb_gpu::DeviceLimits;

/// The largest image edge accepted.
pub const MAX_EDGE: u32 = 16384;

/// Parses `WxH` (`x` or `X`), each side in `1..=16384`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got `{s}`"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|e| format!("bad size `{s}`: {e}"))
    };
    let (w, h) = (p(w)?, p(h)?);
    if w == 0 || h == 0 || w > MAX_EDGE || h > MAX_EDGE {
        return Err(format!("size must be 1..={MAX_EDGE} per side, got {w}x{h}"));
    }
    Ok((w, h))
}

/// Parses a sample count of the CPU reference: 1 to 1024, one jittered ray per stratum
/// of the most nearly square grid.
pub fn parse_samples(s: &str) -> Result<u32, String> {
    let n: u32 = s
        .trim()
        .parse()
        .map_err(|e| format!("bad sample count `{s}`: {e}"))?;
    ssbvb_voxel::reference::SampleGrid::from_count(n)
        .map(|g| g.count())
        .map_err(|e| e.to_string())
}

/// Parses device limits: `adapter` (the adapter's own) or `webgpu` (WebGPU's defaults and
/// no optional feature).
pub fn parse_limits(s: &str) -> Result<DeviceLimits, String> {
    match s.trim() {
        "adapter" => Ok(DeviceLimits::Adapter),
        "webgpu" => Ok(DeviceLimits::WebGpuDefaults),
        other => Err(format!(
            "`{other}`: expected adapter (the adapter's own limits) or webgpu (WebGPU's \
             defaults and no optional feature)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_limits_parse_and_bad_ones_say_why() {
        assert_eq!(parse_size("1280x720"), Ok((1280, 720)));
        assert_eq!(parse_size(" 3X 4"), Ok((3, 4)));
        for bad in ["1280", "0x10", "10x16385", "ax3", "-1x3"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_limits("webgpu"), Ok(DeviceLimits::WebGpuDefaults));
        assert!(
            parse_limits("big")
                .unwrap_err()
                .contains("expected adapter")
        );
    }
}
