//! The sub-pixel jitter of frames whose pipeline asks for it
//! ([`super::node::PassNode::jittered_lod_bias`]): what a temporal pass averages.

/// Frames of the jitter sequence before it repeats.
pub const JITTER_PERIOD: u64 = 16;

/// The sub-pixel offset of frame `i` (pixels, in (-0.5, 0.5)²): the Halton (2, 3) sequence.
pub fn jitter(i: u64) -> [f64; 2] {
    let k = i % JITTER_PERIOD + 1;
    [halton(k, 2) - 0.5, halton(k, 3) - 0.5]
}

fn halton(mut k: u64, base: u64) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while k > 0 {
        f /= base as f64;
        r += f * (k % base) as f64;
        k /= base;
    }
    r
}
