//! The page's side of the voxelizing worker ([`crate::worker`]): one model at a time is
//! sent to it and awaited, its progress shown in the status line. Where no module worker
//! can be started (an old browser), the model is prepared on the page's thread instead.

use std::cell::{Cell, RefCell};

use futures_channel::oneshot;
use ssbvb_voxel::asset::VoxelAsset;
use wasm_bindgen::prelude::*;

use crate::dom::{status, yield_now};
use crate::{WebError, asset_bytes, scene_build};

type Reply = oneshot::Sender<Result<Vec<u8>, String>>;

thread_local! {
    static WORKER: RefCell<Option<web_sys::Worker>> = const { RefCell::new(None) };
    static PENDING: RefCell<Option<Reply>> = const { RefCell::new(None) };
    static LABEL: RefCell<String> = const { RefCell::new(String::new()) };
    static UPDATES: Cell<u32> = const { Cell::new(0) };
    static PREPARED_IN_WORKER: Cell<u32> = const { Cell::new(0) };
    static WARNINGS: RefCell<Vec<String>> = const { RefCell::new(Vec::new()) };
}

/// The warnings of the models prepared since the last call (a missing material or
/// texture), each naming its file.
pub fn take_warnings() -> Vec<String> {
    WARNINGS.with(|w| std::mem::take(&mut *w.borrow_mut()))
}

/// Progress messages shown so far, and models prepared in the worker.
pub fn counts() -> (u32, u32) {
    (UPDATES.with(Cell::get), PREPARED_IN_WORKER.with(Cell::get))
}

/// Prepares the model `name` at `level` in the worker (on the page's thread where there is
/// none), showing its progress.
pub async fn prepare(name: &str, bytes: Vec<u8>, level: u32) -> Result<VoxelAsset, WebError> {
    let label = format!("voxelizing {name} at level {level}");
    status(&label);
    LABEL.with(|l| *l.borrow_mut() = label);
    let Some(worker) = worker() else {
        yield_now().await;
        let (asset, warnings) = scene_build::prepare_model(&bytes, name, level)?;
        WARNINGS.with(|w| w.borrow_mut().extend(warnings));
        return Ok(asset);
    };
    let (tx, rx) = oneshot::channel();
    PENDING.with(|p| *p.borrow_mut() = Some(tx));
    let message = js_sys::Object::new();
    let set = |k: &str, v: &JsValue| {
        let _ = js_sys::Reflect::set(&message, &k.into(), v);
    };
    let array = js_sys::Uint8Array::from(&bytes[..]);
    set("name", &name.into());
    set("bytes", &array);
    set("level", &level.into());
    let transfer = js_sys::Array::of1(&array.buffer());
    if let Err(e) = worker.post_message_with_transfer(&message, &transfer) {
        PENDING.with(|p| p.borrow_mut().take());
        return Err(WebError::Model {
            name: name.to_string(),
            message: format!("cannot send it to the worker: {e:?}"),
        });
    }
    let reply = rx
        .await
        .unwrap_or_else(|_| Err("the worker went away".into()));
    let asset = reply
        .map_err(|message| WebError::Model {
            name: name.to_string(),
            message: message
                .strip_prefix(&format!("{name}: "))
                .unwrap_or(&message)
                .to_string(),
        })
        .and_then(|b| asset_bytes::decode(&b))?;
    PREPARED_IN_WORKER.with(|n| n.set(n.get() + 1));
    Ok(asset)
}

fn reply(r: Result<Vec<u8>, String>) {
    if let Some(tx) = PENDING.with(|p| p.borrow_mut().take()) {
        let _ = tx.send(r);
    }
}

/// The worker, started on first use; `None` where the browser cannot start it.
fn worker() -> Option<web_sys::Worker> {
    if let Some(w) = WORKER.with(|w| w.borrow().clone()) {
        return Some(w);
    }
    let options = web_sys::WorkerOptions::new();
    options.set_type(web_sys::WorkerType::Module);
    let worker = web_sys::Worker::new_with_options("worker.js", &options).ok()?;
    let on_message = Closure::<dyn FnMut(web_sys::MessageEvent)>::new(on_message);
    worker.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
    on_message.forget();
    let on_error = Closure::<dyn FnMut(web_sys::ErrorEvent)>::new(|e: web_sys::ErrorEvent| {
        e.prevent_default();
        reply(Err(format!(
            "the voxelizing worker failed: {}",
            e.message()
        )));
    });
    worker.set_onerror(Some(on_error.as_ref().unchecked_ref()));
    on_error.forget();
    WORKER.with(|w| *w.borrow_mut() = Some(worker.clone()));
    Some(worker)
}

fn on_message(e: web_sys::MessageEvent) {
    let data = e.data();
    let get = |k: &str| js_sys::Reflect::get(&data, &k.into()).unwrap_or(JsValue::UNDEFINED);
    if let Some(stage) = get("stage").as_string() {
        let (done, total) = (
            get("done").as_f64().unwrap_or(0.0),
            get("total").as_f64().unwrap_or(0.0),
        );
        let label = LABEL.with(|l| l.borrow().clone());
        let share = if total > 0.0 {
            format!(" {:.0} %", 100.0 * done / total)
        } else {
            String::new()
        };
        status(&format!("{label}: {stage}{share}"));
        UPDATES.with(|n| n.set(n.get() + 1));
    } else if let Some(warning) = get("warning").as_string() {
        WARNINGS.with(|w| w.borrow_mut().push(warning));
    } else if let Some(message) = get("error").as_string() {
        reply(Err(message));
    } else {
        let asset = get("asset");
        if asset.is_instance_of::<js_sys::Uint8Array>() {
            reply(Ok(js_sys::Uint8Array::from(asset).to_vec()));
        } else {
            reply(Err("the worker sent no asset".into()));
        }
    }
}
