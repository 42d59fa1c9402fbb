//! The counters of the ray-casting baselines (`DenseDda`, `OctreeRayCast`): per frame the
//! pixels that cast a ray and the loop iterations their traces took (DDA cells, or octree
//! nodes visited), counted in the fragment shader (`shaders/ray_cast.inc.wgsl`) into 64
//! lanes of (rays, steps low, steps high) so the atomics do not all hit one address.

use ssbvb_gpu::{GpuContext, wgpu};

use crate::error::PassError;

/// Lanes of the counter buffer (`COUNTER_LANES` in the WGSL).
pub const LANES: usize = 64;

/// Words per lane: rays, then the steps' low and high words.
const LANE_WORDS: usize = 3;

/// A pass's counter buffer: `LANES` × (rays, steps low, steps high) `u32`s.
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

    /// The last frame's rays and their mean steps (`None` without rays), or `None` when
    /// the last frame did not count.
    pub fn read(&self, ctx: &GpuContext) -> Result<Option<(u64, Option<f64>)>, PassError> {
        if !self.counted {
            return Ok(None);
        }
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&ctx.read_buffer(&self.buffer)?);
        Ok(Some(sum_lanes(&words)))
    }
}

/// Rays and mean steps per ray from the lanes' (rays, steps low, steps high) words.
pub fn sum_lanes(words: &[u32]) -> (u64, Option<f64>) {
    let (mut rays, mut steps) = (0u64, 0u64);
    for lane in words.chunks_exact(LANE_WORDS) {
        rays += lane[0] as u64;
        steps += lane[1] as u64 | (lane[2] as u64) << 32;
    }
    (rays, (rays > 0).then(|| steps as f64 / rays as f64))
}

#[cfg(test)]
mod tests {
    #[test]
    fn lanes_sum_into_a_mean() {
        let mut words = vec![0u32; super::LANE_WORDS * super::LANES];
        words[0] = 3;
        words[1] = 30;
        words[3 * 63] = 1;
        words[3 * 63 + 1] = 2;
        assert_eq!(super::sum_lanes(&words), (4, Some(8.0)));
        // A carried high word counts 2^32 steps.
        words[3 * 5] = 4;
        words[3 * 5 + 2] = 1;
        assert_eq!(
            super::sum_lanes(&words).1,
            Some((32.0 + 4294967296.0) / 8.0)
        );
        assert_eq!(super::sum_lanes(&[0; 6]), (0, None));
        let src = ssbvb_gpu::shaders::source("dense_dda.wgsl").unwrap();
        assert!(src.contains(&format!("const COUNTER_LANES: u32 = {}u;", super::LANES)));
    }
}
