//! Hardware-independent counts of what a frame did (`render --json` key `counters`, and
//! the bench): on a software adapter they say more than wall time, and on any adapter
//! they explain it. Each pass fills what it knows ([`super::node::PassNode::counters`]); a
//! count no pass of the pipeline measures stays `None` and is left out of the JSON.

/// The counts of one frame.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct FrameCounters {
    /// Rays the ray-march filter cast (pixels whose prepass entry named an instance).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub filter_rays: Option<u64>,
    /// Mean march loop iterations per filter ray (cells, pages and coarse blocks alike,
    /// over every instance the ray marched).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub march_steps_mean: Option<f64>,
    /// 99th percentile of march steps per filter ray, an upper bound with 1/8 resolution
    /// above 32 steps (from a histogram).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub march_steps_p99: Option<u64>,
    /// Tiles of 16 × 16 prepass texels the filter launched (those holding a proxy): its
    /// workgroups. A software adapter pays for every pixel of a launched tile.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub filter_tiles: Option<u64>,
    /// Mean instance-hierarchy boxes tested per filter ray (0 with one visible instance).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub instance_boxes_per_ray: Option<f64>,
    /// Mean instances marched per filter ray (at least the prepass's own).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub instances_marched_per_ray: Option<f64>,
    /// Billboards the billboard pass drew (the SSBVB fill count).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub billboards_drawn: Option<u64>,
    /// Fragment-shader invocations of the billboard passes (a pipeline-statistics query;
    /// `None` where the adapter lacks `PIPELINE_STATISTICS_QUERY`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub billboard_fragments: Option<u64>,
    /// `billboard_fragments` per pixel showing a voxel: the billboards' overdraw.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fragments_per_covered_pixel: Option<f64>,
    /// Pixels whose ray a ray-casting baseline traced into at least one instance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ray_cast_rays: Option<u64>,
    /// Tiles of 16 × 16 pixels the compute form of a ray caster launched (those some
    /// visible instance's box may cover); `None` for the fragment form.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ray_cast_tiles: Option<u64>,
    /// Dense DDA: mean cells stepped per traced ray (over every instance it traced).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dda_steps_per_ray: Option<f64>,
    /// Octree ray casting: mean nodes visited per traced ray.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub octree_nodes_per_ray: Option<f64>,
    /// Words of the acceleration structure read per traversal step: lookup nodes (3 words)
    /// per march step of the filter, octree nodes (2 words) per step of the octree and
    /// ESVO casters, dense-grid texels (1 word) per DDA cell.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node_words_per_step: Option<f64>,
    /// Pixels whose stencil says voxel at the end of the frame (the denominator of
    /// `fragments_per_covered_pixel`; not reported on its own).
    #[serde(skip)]
    pub voxel_pixels: Option<u64>,
}

impl FrameCounters {
    /// Fills the measures that combine several passes' counts: the billboard fragments per
    /// pixel showing a voxel.
    pub fn derive(&mut self) {
        if let (Some(f), Some(covered)) = (self.billboard_fragments, self.voxel_pixels) {
            self.fragments_per_covered_pixel = (covered > 0).then(|| f as f64 / covered as f64);
        }
    }
}

/// Bins of the steps-per-ray histogram (`steps_bin` in `ray_march_filter.wgsl`).
pub const STEP_BINS: usize = 256;

/// The histogram bin of a step count: exact below 32, then 8 bins per power of two. The
/// Rust twin of WGSL `steps_bin` (a GPU test checks that they agree).
pub fn steps_bin(s: u32) -> usize {
    if s < 32 {
        return s as usize;
    }
    let e = 31 - s.leading_zeros();
    (32 + (e - 5) * 8 + ((s >> (e - 3)) & 7)) as usize
}

/// The largest step count in bin `b` (inverse of [`steps_bin`]).
pub fn steps_bin_max(b: usize) -> u64 {
    if b < 32 {
        return b as u64;
    }
    let e = (b - 32) / 8 + 5;
    let frac = ((b - 32) % 8) as u64;
    ((8 + frac + 1) << (e - 3)) - 1
}

/// The `q` quantile (0..=1) of a histogram, as the largest count of its bin.
pub fn histogram_quantile(bins: &[u32], q: f64) -> Option<u64> {
    let total: u64 = bins.iter().map(|&c| c as u64).sum();
    if total == 0 {
        return None;
    }
    let want = ((total as f64 * q).ceil() as u64).clamp(1, total);
    let mut seen = 0;
    for (b, &c) in bins.iter().enumerate() {
        seen += c as u64;
        if seen >= want {
            return Some(steps_bin_max(b));
        }
    }
    None
}

/// Checks a frame's steps-per-ray histogram against the ray and step totals counted beside
/// it: it holds every ray once, and the steps lie between the sums of its bins' smallest
/// and largest counts (exact below 32 steps a ray).
pub fn check_steps_histogram(rays: u64, steps: u64, bins: &[u32]) -> Result<(), String> {
    let held: u64 = bins.iter().map(|&c| c as u64).sum();
    if held != rays {
        return Err(format!(
            "the steps histogram holds {held} rays, {rays} were counted"
        ));
    }
    let (mut lo, mut hi) = (0u64, 0u64);
    for (b, &c) in bins.iter().enumerate() {
        let smallest = if b == 0 { 0 } else { steps_bin_max(b - 1) + 1 };
        lo = lo.saturating_add(smallest.saturating_mul(c as u64));
        hi = hi.saturating_add(steps_bin_max(b).saturating_mul(c as u64));
    }
    if !(lo..=hi).contains(&steps) {
        return Err(format!(
            "{steps} march steps counted, the steps histogram allows {lo} to {hi}"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_histogram_must_hold_every_ray_and_bound_the_steps() {
        let mut bins = vec![0u32; STEP_BINS];
        // Rays of 0, 3, 3 and 40 steps: 46 in all; 40 is in the bin of 40..=43.
        for s in [0, 3, 3, 40] {
            bins[steps_bin(s)] += 1;
        }
        assert_eq!(check_steps_histogram(4, 46, &bins), Ok(()));
        assert_eq!(check_steps_histogram(4, 49, &bins), Ok(()));
        let short = check_steps_histogram(4, 45, &bins).unwrap_err();
        assert!(
            short.contains("45") && short.contains("46 to 49"),
            "{short}"
        );
        let over = check_steps_histogram(4, 50, &bins).unwrap_err();
        assert!(over.contains("46 to 49"), "{over}");
        let rays = check_steps_histogram(5, 46, &bins).unwrap_err();
        assert!(rays.contains("holds 4 rays, 5"), "{rays}");
        // Below 32 steps the bins are exact.
        let mut exact = vec![0u32; STEP_BINS];
        exact[7] = 2;
        assert_eq!(check_steps_histogram(2, 14, &exact), Ok(()));
        assert!(check_steps_histogram(2, 15, &exact).is_err());
        assert!(check_steps_histogram(2, 13, &exact).is_err());
        // Nothing counted is consistent; the top bin's sums do not overflow.
        assert_eq!(check_steps_histogram(0, 0, &vec![0; STEP_BINS]), Ok(()));
        let mut top = vec![0u32; STEP_BINS];
        top[steps_bin(u32::MAX)] = u32::MAX;
        let most = steps_bin_max(steps_bin(u32::MAX)) * u32::MAX as u64;
        assert_eq!(check_steps_histogram(u32::MAX as u64, most, &top), Ok(()));
        assert!(check_steps_histogram(u32::MAX as u64, u64::MAX, &top).is_err());
    }

    #[test]
    fn bins_are_monotone_and_cover_each_count_once() {
        let mut last = 0;
        for s in (0..5000u32).chain([u32::MAX / 2, u32::MAX]) {
            let b = steps_bin(s);
            assert!(b >= last && b < STEP_BINS, "{s}: bin {b}");
            last = b;
            assert!(s as u64 <= steps_bin_max(b), "{s} above its bin's max");
            if b > 0 {
                assert!(s as u64 > steps_bin_max(b - 1), "{s} inside bin {}", b - 1);
            }
        }
        assert_eq!(steps_bin(31), 31);
        assert_eq!(steps_bin(32), 32);
        assert_eq!(steps_bin_max(32), 35);
        assert_eq!(steps_bin(36), 33);
        // Relative resolution 1/8 above 32.
        for b in 33..200 {
            let (lo, hi) = (steps_bin_max(b - 1) + 1, steps_bin_max(b));
            assert!((hi - lo + 1) as f64 <= lo as f64 / 8.0 + 1e-9, "bin {b}");
        }
    }

    #[test]
    fn quantile_of_a_histogram() {
        let mut bins = vec![0u32; STEP_BINS];
        bins[3] = 98;
        bins[steps_bin(100)] = 1;
        bins[steps_bin(1000)] = 1;
        assert_eq!(histogram_quantile(&bins, 0.5), Some(3));
        assert_eq!(histogram_quantile(&bins, 0.98), Some(3));
        assert_eq!(
            histogram_quantile(&bins, 0.99),
            Some(steps_bin_max(steps_bin(100)))
        );
        assert_eq!(
            histogram_quantile(&bins, 1.0),
            Some(steps_bin_max(steps_bin(1000)))
        );
        assert_eq!(histogram_quantile(&[0; 4], 0.99), None);
    }
}
