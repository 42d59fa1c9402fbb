//! The calibration of the default pipeline (`ssbvb calibrate`): each SSBVB form that
//! [`crate::forms::FORMS`] marks `calibrated` measured once on an adapter, fastest first,
//! in `calibration.json` beside the asset cache, where the default pipeline's choice
//! ([`crate::choice`]) finds it before its rule.
//!
//! An entry is keyed by the adapter's name, backend, device type and driver (with its
//! version) and the device limits it was measured under: another adapter, another driver
//! version or other limits never use it. A file that cannot be read or parsed is ignored
//! with a warning (the rule chooses; `ssbvb calibrate` writes it anew). The file is written
//! to a temporary name and renamed, so a crash never leaves half of it.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use ssbvb_gpu::AdapterVerdict;

use crate::EngineError;

/// What identifies the adapter an entry was measured on.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct AdapterKey {
    /// Adapter name.
    pub name: String,
    /// Backend (`Vulkan`, `Gl`, …).
    pub backend: String,
    /// Device type (`DiscreteGpu`, `Cpu`, …).
    pub device_type: String,
    /// Driver and driver version.
    pub driver: String,
    /// The device limits (`adapter` or `webgpu`).
    pub limits: String,
}

impl AdapterKey {
    /// The key of a listed adapter under `limits`.
    pub fn of(a: &AdapterVerdict, limits: &str) -> Self {
        Self {
            name: a.name.clone(),
            backend: a.backend.clone(),
            device_type: a.device_type.clone(),
            driver: a.driver.clone(),
            limits: limits.to_string(),
        }
    }
}

/// One form's measured frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FormTime {
    /// Pipeline file, relative to the assets folder.
    pub pipeline: String,
    /// Median frame time, ms.
    pub frame_ms: f64,
    /// `gpu` (summed pass timestamps) or `wall` (submit and wait; software adapters).
    pub clock: String,
}

/// One adapter's calibration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    /// The adapter.
    pub adapter: AdapterKey,
    /// The scene and size measured (the bundled default scene).
    pub scene: String,
    /// Image size.
    pub size: [u32; 2],
    /// Each form that fits the adapter, fastest first.
    pub forms: Vec<FormTime>,
}

impl Entry {
    /// The fastest form's pipeline file (relative to the assets folder).
    pub fn fastest(&self) -> Option<&str> {
        self.forms.first().map(|f| f.pipeline.as_str())
    }

    /// The measured times, for a reason (`pixel 12.1 ms (gpu), …`).
    pub fn summary(&self) -> String {
        let times: Vec<String> = self
            .forms
            .iter()
            .map(|f| format!("{} {:.2} ms ({})", f.pipeline, f.frame_ms, f.clock))
            .collect();
        format!(
            "{} at {}x{}: {}",
            self.scene,
            self.size[0],
            self.size[1],
            times.join(", ")
        )
    }
}

/// The file: a version and the entries.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CalibrationFile {
    /// Format version ([`VERSION`]).
    pub version: u32,
    /// One entry per adapter key.
    pub entries: Vec<Entry>,
}

/// The file format's version.
pub const VERSION: u32 = 1;

/// The forms measured, in the rule's order of preference (ties go to the earlier): the
/// pipeline files of the forms [`crate::forms::FORMS`] marks `calibrated`.
pub fn forms() -> Vec<&'static str> {
    crate::forms::FORMS
        .iter()
        .filter(|f| f.calibrated)
        .map(|f| f.file)
        .collect()
}

/// Where the calibration lives: `calibration.json` in the asset cache's folder.
pub fn path() -> PathBuf {
    ssbvb_voxel::cache::default_cache_dir().join("calibration.json")
}

/// Reads the file: `Ok(None)` where there is none, an error naming the file where it cannot
/// be read or parsed or has another version.
pub fn load(path: &Path) -> Result<Option<CalibrationFile>, EngineError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(EngineError::io(path, e)),
    };
    let file: CalibrationFile = serde_json::from_str(&text).map_err(|e| {
        EngineError::Invalid(format!("{}: not a calibration file: {e}", path.display()))
    })?;
    if file.version != VERSION {
        return Err(EngineError::Invalid(format!(
            "{}: calibration format {} (this ssbvb reads {VERSION})",
            path.display(),
            file.version
        )));
    }
    Ok(Some(file))
}

/// The entry measured on exactly `key`.
pub fn lookup<'a>(file: &'a CalibrationFile, key: &AdapterKey) -> Option<&'a Entry> {
    file.entries.iter().find(|e| &e.adapter == key)
}

/// Writes `entry` into the file at `path`, replacing the entry of the same adapter key and
/// keeping the others (an unreadable file is replaced whole), through a temporary file
/// renamed over it.
pub fn store(path: &Path, entry: Entry) -> Result<(), EngineError> {
    let mut file = load(path).ok().flatten().unwrap_or_default();
    file.version = VERSION;
    file.entries.retain(|e| e.adapter != entry.adapter);
    file.entries.push(entry);
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| EngineError::io(dir, e))?;
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(|e| EngineError::io(dir, e))?;
    serde_json::to_writer_pretty(&mut tmp, &file)
        .map_err(|e| EngineError::io(path, std::io::Error::other(e)))?;
    tmp.as_file()
        .sync_all()
        .map_err(|e| EngineError::io(path, e))?;
    tmp.persist(path)
        .map_err(|e| EngineError::io(path, e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(driver: &str) -> AdapterKey {
        AdapterKey {
            name: "gpu".into(),
            backend: "Vulkan".into(),
            device_type: "DiscreteGpu".into(),
            driver: driver.into(),
            limits: "adapter".into(),
        }
    }

    fn entry(driver: &str, fastest: &str) -> Entry {
        Entry {
            adapter: key(driver),
            scene: "scenes/default.ron".into(),
            size: [64, 48],
            forms: vec![FormTime {
                pipeline: fastest.into(),
                frame_ms: 1.0,
                clock: "gpu".into(),
            }],
        }
    }

    #[test]
    fn entries_are_found_only_under_their_own_adapter_driver_and_limits() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sub/calibration.json");
        assert!(load(&p).unwrap().is_none());
        store(&p, entry("580.1", "pipelines/ssbvb_splat.ron")).unwrap();
        store(&p, entry("580.2", "pipelines/ssbvb_unique.ron")).unwrap();
        // The same key again replaces its entry.
        store(&p, entry("580.2", "pipelines/ssbvb_pixel.ron")).unwrap();
        let f = load(&p).unwrap().unwrap();
        assert_eq!(f.entries.len(), 2);
        let fastest = |k: &AdapterKey| lookup(&f, k).and_then(Entry::fastest);
        assert_eq!(fastest(&key("580.1")), Some("pipelines/ssbvb_splat.ron"));
        assert_eq!(fastest(&key("580.2")), Some("pipelines/ssbvb_pixel.ron"));
        assert_eq!(fastest(&key("575.0")), None);
        let webgpu = AdapterKey {
            limits: "webgpu".into(),
            ..key("580.1")
        };
        assert_eq!(fastest(&webgpu), None);
        // No temporary file is left beside it.
        let names: Vec<_> = std::fs::read_dir(p.parent().unwrap()).unwrap().collect();
        assert_eq!(names.len(), 1);
    }

    #[test]
    fn a_corrupt_or_foreign_file_is_an_error_naming_it_and_is_replaced_by_store() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("calibration.json");
        for bad in [
            "{\"version\": 1, \"entries\": [",
            "not json",
            "{\"version\": 99, \"entries\": []}",
        ] {
            std::fs::write(&p, bad).unwrap();
            let e = format!("{:#}", load(&p).unwrap_err());
            assert!(e.contains("calibration.json"), "{e}");
        }
        store(&p, entry("1", "pipelines/ssbvb_unique.ron")).unwrap();
        assert_eq!(load(&p).unwrap().unwrap().entries.len(), 1);
    }

    #[test]
    fn summaries_list_the_forms_fastest_first() {
        let mut e = entry("1", "pipelines/ssbvb_pixel.ron");
        e.forms.push(FormTime {
            pipeline: "pipelines/ssbvb_unique.ron".into(),
            frame_ms: 3.5,
            clock: "gpu".into(),
        });
        assert_eq!(
            e.summary(),
            "scenes/default.ron at 64x48: pipelines/ssbvb_pixel.ron 1.00 ms (gpu), \
             pipelines/ssbvb_unique.ron 3.50 ms (gpu)"
        );
    }
}
