//! Losing the GPU device mid-run (a driver reset, the GPU removed or switched) and the
//! hidden `--inject-fault device-lost@FRAME` that causes it in tests: what a soak does when
//! its device goes (`crate::soak`: open a new session from the CPU-side state and draw the
//! frame again), and when it gives up.

use anyhow::{Result, bail};

/// Frames within which a second loss after a recovery is an error rather than another
/// recovery: a device that keeps failing is reported, not retried forever.
pub const LOST_AGAIN_WITHIN: usize = 8;

/// A fault to inject (`--inject-fault`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// Destroy the device before soak frame `frame` (`device-lost@FRAME`).
    DeviceLost {
        /// The soak frame (from 0).
        frame: usize,
    },
}

/// Parses `device-lost@FRAME`.
pub fn parse_fault(s: &str) -> Result<Fault, String> {
    let (kind, frame) = s
        .split_once('@')
        .ok_or_else(|| format!("`{s}`: expected KIND@FRAME, e.g. device-lost@10"))?;
    let frame: usize = frame
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: the frame must be a whole number, got `{frame}`"))?;
    match kind.trim() {
        "device-lost" => Ok(Fault::DeviceLost { frame }),
        other => Err(format!(
            "`{s}`: unknown fault `{other}`; known: device-lost@FRAME"
        )),
    }
}

/// Whether a device loss is injected before soak frame `frame`.
pub fn loses_device_at(faults: &[Fault], frame: usize) -> bool {
    faults
        .iter()
        .any(|f| matches!(f, Fault::DeviceLost { frame: at } if *at == frame))
}

/// Checks `faults` against a soak of `frames` frames: each must fall inside it.
pub fn check_faults(faults: &[Fault], frames: u64) -> Result<()> {
    for f in faults {
        let Fault::DeviceLost { frame } = f;
        if frames < 2 || *frame as u64 >= frames {
            bail!(
                "--inject-fault device-lost@{frame} needs a soak of more than {frame} frames \
                 (--frames {} or more): faults are injected into the soak's frames",
                (frame + 1).max(2)
            );
        }
    }
    Ok(())
}

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
    pub fn lost_at(&mut self, frame: usize, reason: &str) -> Result<()> {
        if let Some(last) = self.last
            && frame - last < LOST_AGAIN_WITHIN
        {
            bail!(
                "the GPU device was lost again at frame {frame}, {} frames after it was \
                 recreated at frame {last} ({reason}); giving up rather than retrying",
                frame - last
            );
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
        for bad in [
            "device-lost",
            "device-lost@x",
            "oom@3",
            "@4",
            "device-lost@-1",
        ] {
            assert!(parse_fault(bad).is_err(), "{bad}");
        }
        let f = [Fault::DeviceLost { frame: 5 }];
        assert!(loses_device_at(&f, 5) && !loses_device_at(&f, 4));
        assert!(check_faults(&f, 6).is_ok());
        let e = check_faults(&f, 5).unwrap_err().to_string();
        assert!(e.contains("--frames 6"), "{e}");
        assert!(check_faults(&[Fault::DeviceLost { frame: 0 }], 1).is_err());
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
