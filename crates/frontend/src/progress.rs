//! An indicatif progress bar behind the voxel crate's `Progress` trait.

use indicatif::{ProgressBar, ProgressStyle};

/// Shows voxelization progress on stderr (or nothing when hidden).
pub struct BarProgress {
    bar: ProgressBar,
}

impl BarProgress {
    /// A visible bar when `show`, else a hidden one.
    pub fn new(show: bool) -> Self {
        let bar = if show {
            ProgressBar::new(0)
        } else {
            ProgressBar::hidden()
        };
        if let Ok(style) =
            ProgressStyle::with_template("{msg:>14} [{bar:40}] {pos}/{len} ({elapsed})")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        Self { bar }
    }

    /// Clears the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl ssbvb_voxel::progress::Progress for BarProgress {
    fn begin(&self, stage: &str, total: u64) {
        self.bar.set_message(stage.to_string());
        self.bar.set_length(total);
        self.bar.set_position(0);
    }

    fn advance(&self, units: u64) {
        self.bar.inc(units);
    }
}
