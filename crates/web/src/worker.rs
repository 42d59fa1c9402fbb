//! The page's voxelizing worker (`static/worker.js` runs this module's export in a Web
//! Worker): a model is loaded and prepared off the page's thread, its stages posted to the
//! page as they go, then its load's warnings, and the asset posted back as bytes
//! ([`crate::asset_bytes`]).

use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

use ssbvb_voxel::progress::Progress;
use wasm_bindgen::prelude::*;

use crate::{asset_bytes, scene_build};

/// Prepares the model `name` (its `bytes`) at `level`; the prepared asset's bytes, or the
/// error's message thrown.
#[wasm_bindgen]
pub fn prepare_model_in_worker(name: &str, bytes: &[u8], level: u32) -> Result<Vec<u8>, JsValue> {
    let progress = PostedProgress::default();
    let (asset, warnings) = scene_build::prepare_model_with(bytes, name, level, &progress)
        .map_err(|e| JsValue::from_str(&e.to_string()))?;
    for w in &warnings {
        let message = js_sys::Object::new();
        let _ = js_sys::Reflect::set(&message, &"warning".into(), &w.as_str().into());
        let scope: web_sys::DedicatedWorkerGlobalScope = js_sys::global().unchecked_into();
        let _ = scope.post_message(&message);
    }
    Ok(asset_bytes::encode(&asset))
}

/// Posts `{stage, done, total}` to the page at each stage and each whole percent.
#[derive(Default)]
struct PostedProgress {
    stage: Mutex<String>,
    total: AtomicU64,
    done: AtomicU64,
    shown: AtomicU64,
}

impl Progress for PostedProgress {
    fn begin(&self, stage: &str, total: u64) {
        if let Ok(mut s) = self.stage.lock() {
            *s = stage.to_string();
        }
        self.total.store(total, Ordering::Relaxed);
        self.done.store(0, Ordering::Relaxed);
        self.shown.store(0, Ordering::Relaxed);
        post(stage, 0, total);
    }

    fn advance(&self, units: u64) {
        let done = self.done.fetch_add(units, Ordering::Relaxed) + units;
        let total = self.total.load(Ordering::Relaxed);
        let percent = (done * 100).checked_div(total).unwrap_or(0);
        if self.shown.swap(percent, Ordering::Relaxed) != percent
            && let Ok(stage) = self.stage.lock()
        {
            post(&stage, done, total);
        }
    }
}

fn post(stage: &str, done: u64, total: u64) {
    let message = js_sys::Object::new();
    let set = |k: &str, v: JsValue| {
        let _ = js_sys::Reflect::set(&message, &k.into(), &v);
    };
    set("stage", stage.into());
    set("done", (done as f64).into());
    set("total", (total as f64).into());
    let scope: web_sys::DedicatedWorkerGlobalScope = js_sys::global().unchecked_into();
    let _ = scope.post_message(&message);
}
