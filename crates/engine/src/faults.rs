//! GPU faults and the hidden `--inject-fault` that causes them in tests (`render`, `view`
//! and `bench` take it).
//!
//! - **Device loss** (a driver reset, the GPU removed or switched): a soak opens a new
//!   session from the CPU-side state and draws the frame again (`ssbvb render`), the viewer
//!   rebuilds every GPU resource (`ssbvb view`), the bench reports the row failed and
//!   goes on on a new device; a device lost again soon after is an error.
//! - **Out of memory**: an allocation the driver refuses is
//!   [`ssbvb_gpu::GpuError::OutOfMemory`] naming the resource and its size
//!   (`ssbvb_gpu::alloc`). Under a `--gpu-budget` the session is opened again under half
//!   the budget (so the level cap falls where the view's pages no longer fit) until it
//!   fits; without one the error names the flag ([`out_of_memory_hint`]).
//!
//! Injected, `oom@FRAME` arms a refusal of the next large allocation before frame FRAME
//! and has the command rebuild its GPU session there (as after a device loss, or as the
//! viewer does when its budget changes), so the refusal lands in the rebuild; `render`
//! without a soak and the viewer at frame 0 refuse in their first upload. A refusal that
//! did not fire is disarmed once the work it was meant for is done.

use ssbvb_gpu::{GpuError, ResourceError};
use ssbvb_passes::PassError;

use crate::EngineError;

/// Frames within which a second loss after a recovery is an error rather than another
/// recovery: a device that keeps failing is reported, not retried forever.
pub const LOST_AGAIN_WITHIN: usize = 8;

/// A fault to inject (`--inject-fault`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// Destroy the device before frame `frame` (`device-lost@FRAME`).
    DeviceLost {
        /// The frame (from 0).
        frame: usize,
    },
    /// Refuse the next large allocation and rebuild the session before frame `frame`
    /// (`oom@FRAME`).
    OutOfMemory {
        /// The frame (from 0).
        frame: usize,
    },
}

impl Fault {
    /// The frame it is injected before.
    pub fn frame(&self) -> usize {
        match self {
            Fault::DeviceLost { frame } | Fault::OutOfMemory { frame } => *frame,
        }
    }

    /// As written on the command line.
    pub fn spelled(&self) -> String {
        match self {
            Fault::DeviceLost { frame } => format!("device-lost@{frame}"),
            Fault::OutOfMemory { frame } => format!("oom@{frame}"),
        }
    }
}

/// Parses `device-lost@FRAME` or `oom@FRAME`.
pub fn parse_fault(s: &str) -> Result<Fault, String> {
    let (kind, frame) = s
        .split_once('@')
        .ok_or_else(|| format!("`{s}`: expected KIND@FRAME, e.g. device-lost@10 or oom@3"))?;
    let frame: usize = frame
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: the frame must be a whole number, got `{frame}`"))?;
    match kind.trim() {
        "device-lost" => Ok(Fault::DeviceLost { frame }),
        "oom" => Ok(Fault::OutOfMemory { frame }),
        other => Err(format!(
            "`{s}`: unknown fault `{other}`; known: device-lost@FRAME, oom@FRAME"
        )),
    }
}

/// Whether a device loss is injected before frame `frame`.
pub fn loses_device_at(faults: &[Fault], frame: usize) -> bool {
    faults.contains(&Fault::DeviceLost { frame })
}

/// Whether an out-of-memory refusal is injected before frame `frame`.
pub fn runs_out_of_memory_at(faults: &[Fault], frame: usize) -> bool {
    faults.contains(&Fault::OutOfMemory { frame })
}

/// Checks `faults` against a render of `frames` frames (1: no soak): each must fall
/// inside it. A device loss needs a soak (the first frame has no device to lose yet); an
/// out-of-memory fault at frame 0 hits the first upload.
pub fn check_faults(faults: &[Fault], frames: u64) -> Result<(), EngineError> {
    for f in faults {
        let frame = f.frame();
        let ok = match f {
            Fault::DeviceLost { .. } => frames >= 2 && (frame as u64) < frames,
            Fault::OutOfMemory { .. } => frame == 0 || (frame as u64) < frames,
        };
        if !ok {
            return Err(EngineError::Invalid(format!(
                "--inject-fault {} needs a soak of more than {frame} frames (--frames {} or \
                 more): faults are injected into the soak's frames",
                f.spelled(),
                frame.saturating_add(1).max(2)
            )));
        }
    }
    Ok(())
}

/// The refused allocation (resource, bytes) when `e`, or any error it wraps (its
/// `source()` chain: an `anyhow` context, an [`EngineError`], a pass or resource error),
/// is an out-of-memory error from the driver.
pub fn out_of_memory(e: &(dyn std::error::Error + 'static)) -> Option<(String, u64)> {
    use crate::error::{refused_by_gpu, refused_by_pass, refused_by_resource};
    let mut next = Some(e);
    while let Some(c) = next {
        let found = if let Some(engine) = c.downcast_ref::<EngineError>() {
            engine.refused_allocation()
        } else if let Some(g) = c.downcast_ref::<GpuError>() {
            refused_by_gpu(g)
        } else if let Some(r) = c.downcast_ref::<ResourceError>() {
            refused_by_resource(r)
        } else {
            c.downcast_ref::<PassError>().and_then(refused_by_pass)
        };
        if found.is_some() {
            return found;
        }
        next = c.source();
    }
    None
}

pub use crate::session::{
    INJECTED_OOM_MIN_BYTES, frame_out_of_memory_hint, is_scene_resource, out_of_memory_hint,
};

/// The recoveries of one run and the rule on repeated losses.
#[derive(Debug, Default)]
pub struct Recoveries {
    /// Devices recreated so far.
    pub count: usize,
    last: Option<usize>,
}

impl Recoveries {
    /// Records a loss at soak frame `frame`, or fails when it comes within
    /// [`LOST_AGAIN_WITHIN`] frames of the last recovery.
    pub fn lost_at(&mut self, frame: usize, reason: &str) -> Result<(), EngineError> {
        if let Some(last) = self.last
            && frame
                .checked_sub(last)
                .is_some_and(|d| d < LOST_AGAIN_WITHIN)
        {
            return Err(EngineError::Invalid(format!(
                "the GPU device was lost again at frame {frame}, {} frames after it was \
                 recreated at frame {last} ({reason}); giving up rather than retrying",
                frame.saturating_sub(last)
            )));
        }
        self.count += 1;
        self.last = Some(frame);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_parse_and_are_checked_against_the_soak() {
        assert_eq!(
            parse_fault("device-lost@12"),
            Ok(Fault::DeviceLost { frame: 12 })
        );
        assert_eq!(parse_fault("oom@3"), Ok(Fault::OutOfMemory { frame: 3 }));
        for bad in [
            "device-lost",
            "device-lost@x",
            "oom",
            "leak@3",
            "@4",
            "oom@-1",
        ] {
            let e = parse_fault(bad).unwrap_err();
            assert!(e.contains(bad), "{bad}: {e}");
        }
        let f = [Fault::DeviceLost { frame: 5 }];
        assert!(loses_device_at(&f, 5) && !loses_device_at(&f, 4));
        assert!(!runs_out_of_memory_at(&f, 5));
        assert!(check_faults(&f, 6).is_ok());
        let e = check_faults(&f, 5).unwrap_err().to_string();
        assert!(
            e.contains("--frames 6") && e.contains("device-lost@5"),
            "{e}"
        );
        assert!(check_faults(&[Fault::DeviceLost { frame: 0 }], 1).is_err());
        // Out of memory at the first upload needs no soak; later frames do.
        let oom = |frame| [Fault::OutOfMemory { frame }];
        assert!(runs_out_of_memory_at(&oom(0), 0));
        assert!(check_faults(&oom(0), 1).is_ok());
        assert!(check_faults(&oom(1), 1).is_err());
        assert!(check_faults(&oom(9), 10).is_ok() && check_faults(&oom(10), 10).is_err());
    }

    #[test]
    fn a_refused_allocation_is_found_through_every_wrapper() {
        let refused = || GpuError::OutOfMemory {
            resource: "voxel colours 0".into(),
            bytes: 3 << 20,
        };
        let want = Some(("voxel colours 0".to_string(), 3 << 20));
        let direct = refused();
        assert_eq!(out_of_memory(&direct), want);
        let scene = EngineError::Resource(ResourceError::Gpu(refused())).context("opening");
        assert_eq!(out_of_memory(&scene), want);
        let pass = PassError::Resource(ResourceError::Gpu(refused()));
        assert_eq!(out_of_memory(&pass), want);
        assert_eq!(out_of_memory(&PassError::Gpu(refused())), want);
        // Wrapped as a source of another error (how `anyhow` contexts chain).
        #[derive(Debug, thiserror::Error)]
        #[error("rendering")]
        struct Outer(#[source] PassError);
        assert_eq!(out_of_memory(&Outer(PassError::Gpu(refused()))), want);
        let other = ResourceError::TooLarge("x".into());
        assert_eq!(out_of_memory(&other), None);
        assert!(
            refused()
                .to_string()
                .contains("3.0 MiB for voxel colours 0")
        );
    }

    #[test]
    fn a_loss_soon_after_a_recovery_is_an_error() {
        let mut r = Recoveries::default();
        r.lost_at(3, "x").unwrap();
        let e = r
            .lost_at(3 + LOST_AGAIN_WITHIN - 1, "again")
            .unwrap_err()
            .to_string();
        assert!(e.contains("lost again") && e.contains("again"), "{e}");
        r.lost_at(3 + LOST_AGAIN_WITHIN, "later").unwrap();
        assert_eq!(r.count, 2);
    }
}
