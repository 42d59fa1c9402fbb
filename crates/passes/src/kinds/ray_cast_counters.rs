//! The counters of the ray-casting baselines (`DenseDda`, `OctreeRayCast`, `EsvoRayCast`):
//! per frame the pixels that cast a ray, the loop iterations their traces took (DDA cells,
//! or octree nodes visited) and the words of the grid or octree they read, counted in the
//! fragment shader (`shaders/ray_cast.inc.wgsl`) into 64 lanes of (rays, steps low, steps
//! high, words low, words high) so the atomics do not all hit one address.

use ssbvb_gpu::{GpuContext, wgpu};

use crate::error::PassError;

/// Lanes of the counter buffer (`COUNTER_LANES` in the WGSL).
pub const LANES: usize = 64;

/// Words per lane: rays, then the steps' and the words' low and high words.
const LANE_WORDS: usize = 5;

/// A pass's counter buffer: `LANES` × `LANE_WORDS` `u32`s.
pub struct RayCastCounters {
    buffer: wgpu::Buffer,
    /// Whether the last recorded frame counted (`Recorder::counting`).
    counted: bool,
}

impl RayCastCounters {
    /// A zeroed counter buffer.
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("ray cast counters"),
                size: (LANES * LANE_WORDS * 4) as u64,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            counted: false,
        }
    }

    /// The buffer, for the pass's bind group (`ray_counters`).
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        self.buffer.as_entire_binding()
    }

    /// Starts a frame: records the clear when the frame counts (`counting`).
    pub fn begin_frame(&mut self, encoder: &mut wgpu::CommandEncoder, counting: bool) {
        self.counted = counting;
        if counting {
            encoder.clear_buffer(&self.buffer, 0, None);
        }
    }

    /// The last frame's counts, or `None` when the last frame did not count.
    pub fn read(&self, ctx: &GpuContext) -> Result<Option<RayCastCounts>, PassError> {
        if !self.counted {
            return Ok(None);
        }
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&ctx.read_buffer(&self.buffer)?);
        Ok(Some(sum_lanes(&words)))
    }
}

/// One frame's counts of a ray caster.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayCastCounts {
    /// Pixels that traced a ray into at least one instance.
    pub rays: u64,
    /// Mean loop iterations per ray (`None` without rays).
    pub steps_per_ray: Option<f64>,
    /// Mean words of the grid or octree read per iteration (`None` without steps).
    pub words_per_step: Option<f64>,
}

/// The counts from the lanes' (rays, steps low, steps high, words low, words high) words.
pub fn sum_lanes(words: &[u32]) -> RayCastCounts {
    let (mut rays, mut steps, mut read) = (0u64, 0u64, 0u64);
    for lane in words.chunks_exact(LANE_WORDS) {
        rays += lane[0] as u64;
        steps += lane[1] as u64 | (lane[2] as u64) << 32;
        read += lane[3] as u64 | (lane[4] as u64) << 32;
    }
    RayCastCounts {
        rays,
        steps_per_ray: (rays > 0).then(|| steps as f64 / rays as f64),
        words_per_step: (steps > 0).then(|| read as f64 / steps as f64),
    }
}

#[cfg(test)]
mod tests {
    use super::{LANE_WORDS, LANES, sum_lanes};

    #[test]
    fn lanes_sum_into_means() {
        let mut words = vec![0u32; LANE_WORDS * LANES];
        words[0] = 3;
        words[1] = 30;
        words[3] = 60;
        let last = LANE_WORDS * 63;
        words[last] = 1;
        words[last + 1] = 2;
        words[last + 3] = 4;
        let c = sum_lanes(&words);
        assert_eq!((c.rays, c.steps_per_ray), (4, Some(8.0)));
        assert_eq!(c.words_per_step, Some(2.0));
        // A carried high word counts 2^32 steps (or words).
        words[LANE_WORDS * 5] = 4;
        words[LANE_WORDS * 5 + 2] = 1;
        words[LANE_WORDS * 5 + 4] = 1;
        let c = sum_lanes(&words);
        assert_eq!(c.steps_per_ray, Some((32.0 + 4294967296.0) / 8.0));
        assert_eq!(
            c.words_per_step,
            Some((64.0 + 4294967296.0) / (32.0 + 4294967296.0))
        );
        let none = sum_lanes(&[0; 2 * LANE_WORDS]);
        assert_eq!(
            (none.rays, none.steps_per_ray, none.words_per_step),
            (0, None, None)
        );
        let src = ssbvb_gpu::shaders::source("dense_dda.wgsl").unwrap();
        assert!(src.contains(&format!("const COUNTER_LANES: u32 = {LANES}u;")));
        assert!(src.contains(&format!("const COUNTER_LANE_WORDS: u32 = {LANE_WORDS}u;")));
    }
}
