//! Helpers the voxelizer's test files share: a deterministic source of numbers and the
//! expected occupancy-gradient normal, worked out independently of the code under test.

use glam::DVec3;

/// Xorshift64 numbers in [0, 1) from a fixed seed: the same sequence on every call.
pub(super) fn unit_randoms() -> impl FnMut() -> f64 {
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The expected normal of cell `c` of a level-`n`-wide grid whose occupied cells are those
/// `occupied` accepts: away from its occupied 26-neighbours (each at unit weight), or the
/// direction from the grid's centre where they cancel. Also whether it fell back to that.
pub(super) fn expected_normal(
    occupied: impl Fn(&[i64; 3]) -> bool,
    c: [i64; 3],
    n: i64,
) -> (DVec3, bool) {
    let mut g = DVec3::ZERO;
    for d in (0..27).map(|k| [k % 3 - 1, k / 3 % 3 - 1, k / 9 - 1]) {
        if d != [0; 3] && occupied(&[c[0] + d[0], c[1] + d[1], c[2] + d[2]]) {
            let d = DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64);
            g -= d / d.length();
        }
    }
    let from_centre = DVec3::from(c.map(|x| x as f64 + 0.5 - n as f64 / 2.0));
    let fallback = g.length() <= 1e-12;
    (if fallback { from_centre } else { g }.normalize(), fallback)
}
