//! Every command buffer ssbvb submits goes through [`GpuContext::submit`], named by what it
//! does, so that the longest single submission of a command can be measured: a driver
//! resets the GPU when one runs too long (Windows after about two seconds), so work that
//! could take that long on a real GPU must be split into bounded submissions. With
//! [`GpuContext::time_submissions`] on, each submission is timed alone (earlier work is
//! waited for first, then the submission itself); that serializes the CPU and the GPU, so
//! it is for measuring (`--time-submissions`), not for frames that are timed otherwise.

use std::collections::BTreeMap;
use web_time::Instant;

use serde::Serialize;

use crate::GpuContext;

/// Per kind of submission, its timings, while timing is on.
pub(crate) type SubmissionLog =
    std::sync::Arc<std::sync::Mutex<Option<BTreeMap<String, SubmissionTimes>>>>;

/// The timings of the submissions of one kind.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SubmissionTimes {
    /// What the submissions do (`frame`, `exact voxelization: fragments`, …).
    pub what: String,
    /// How many were timed.
    pub count: u64,
    /// The longest, from submission to completion, in milliseconds.
    pub max_ms: f64,
    /// All of them together.
    pub total_ms: f64,
}

impl GpuContext {
    /// Starts (or stops) timing each submission alone; starting clears earlier timings.
    pub fn time_submissions(&self, on: bool) {
        if let Ok(mut log) = self.submission_log.lock() {
            *log = on.then(BTreeMap::new);
        }
    }

    /// Submits `buffers` (one unit of work named `what`); timed when
    /// [`GpuContext::time_submissions`] is on.
    pub fn submit(&self, what: &str, buffers: impl IntoIterator<Item = wgpu::CommandBuffer>) {
        let timing = self.submission_log.lock().is_ok_and(|l| l.is_some());
        if !timing {
            self.queue.submit(buffers);
            return;
        }
        // Earlier work first, so the time is this submission's alone.
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
        let t0 = Instant::now();
        self.queue.submit(buffers);
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        if let Ok(mut log) = self.submission_log.lock()
            && let Some(log) = log.as_mut()
        {
            let t = log.entry(what.to_string()).or_insert(SubmissionTimes {
                what: what.to_string(),
                count: 0,
                max_ms: 0.0,
                total_ms: 0.0,
            });
            t.count += 1;
            t.max_ms = t.max_ms.max(ms);
            t.total_ms += ms;
        }
    }

    /// The submissions timed so far, the longest first (empty when timing is off).
    pub fn submission_times(&self) -> Vec<SubmissionTimes> {
        let mut v: Vec<SubmissionTimes> = self
            .submission_log
            .lock()
            .ok()
            .and_then(|l| l.as_ref().map(|m| m.values().cloned().collect()))
            .unwrap_or_default();
        v.sort_by(|a, b| b.max_ms.total_cmp(&a.max_ms));
        v
    }
}
