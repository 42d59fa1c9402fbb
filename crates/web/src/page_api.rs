//! What scripts and the user reach: `window.ssbvb` (`readPixels`, `readVoxelMask`,
//! `loadModel`, `renderFrames`, `stats`), the scene and pipeline menus, the model file
//! input and drop, the orbit camera's pointer and wheel input, and the frame loop.

use std::rc::Rc;

use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::future_to_promise;

use crate::app::{App, draw_and_report, load_model};
use crate::dom::{document, element, show_error};
use crate::params::{PageParams, SCENES, pipelines};

/// Fills the scene and pipeline menus and makes a choice reload the page with it.
pub fn setup_controls(params: &PageParams) {
    let fill = |id: &str, names: &[&str], first: Option<&str>, chosen: &str| {
        let Some(select) = element::<web_sys::HtmlSelectElement>(id) else {
            return;
        };
        let options: Vec<&str> = first.into_iter().chain(names.iter().copied()).collect();
        for name in options {
            if let Ok(o) = document().create_element("option") {
                o.set_text_content(Some(name));
                let _ = o.set_attribute("value", name);
                if name == chosen {
                    let _ = o.set_attribute("selected", "");
                }
                let _ = select.append_child(&o);
            }
        }
        let on_change = Closure::<dyn FnMut()>::new(reload_with_choices);
        select.set_onchange(Some(on_change.as_ref().unchecked_ref()));
        on_change.forget();
    };
    fill("scene", SCENES, None, &params.scene);
    let chosen = params.pipeline.as_deref().unwrap_or("default");
    fill("pipeline", &pipelines(), Some("default"), chosen);
}

fn reload_with_choices() {
    let value = |id: &str| {
        element::<web_sys::HtmlSelectElement>(id)
            .map(|s| s.value())
            .unwrap_or_default()
    };
    let Ok(query) = web_sys::UrlSearchParams::new() else {
        return;
    };
    query.set("scene", &value("scene"));
    let pipeline = value("pipeline");
    if pipeline != "default" {
        query.set("pipeline", &pipeline);
    }
    if let Some(w) = web_sys::window() {
        let old =
            web_sys::UrlSearchParams::new_with_str(&w.location().search().unwrap_or_default());
        if let Some(size) = old.ok().and_then(|o| o.get("size")) {
            query.set("size", &size);
        }
        let _ = w.location().set_search(&String::from(query.to_string()));
    }
}

/// Sets up `window.ssbvb`.
pub fn install(app: Rc<App>) {
    let api = js_sys::Object::new();
    let set = |name: &str, f: &JsValue| {
        let _ = js_sys::Reflect::set(&api, &name.into(), f);
    };
    let a = app.clone();
    let read_pixels = Closure::<dyn FnMut() -> js_sys::Promise>::new(move || {
        let a = a.clone();
        future_to_promise(async move {
            let texture = a.view.borrow().renderer.output().texture.clone();
            let data = a
                .ctx
                .read_texture_async(&texture, ssbvb_gpu::wgpu::TextureAspect::All)
                .await
                .and_then(|d| d.to_rgba8())
                .map_err(|e| JsValue::from_str(&e.to_string()))?;
            Ok(js_sys::Uint8Array::from(&data[..]).into())
        })
    });
    set("readPixels", read_pixels.as_ref());
    read_pixels.forget();
    let a = app.clone();
    let read_mask = Closure::<dyn FnMut() -> js_sys::Promise>::new(move || {
        let a = a.clone();
        future_to_promise(async move {
            let texture = ssbvb_passes::measure::voxel_mask_texture(&a.view.borrow().renderer);
            let Some(texture) = texture else {
                return Ok(JsValue::NULL);
            };
            let mask = ssbvb_passes::measure::read_voxel_mask_async(&a.ctx, &texture)
                .await
                .map_err(|e| JsValue::from_str(&e.to_string()))?;
            Ok(js_sys::Uint8Array::from(&mask[..]).into())
        })
    });
    set("readVoxelMask", read_mask.as_ref());
    read_mask.forget();
    let a = app.clone();
    let load = Closure::<dyn FnMut(String, js_sys::Uint8Array, u32) -> js_sys::Promise>::new(
        move |name: String, bytes: js_sys::Uint8Array, level: u32| {
            let a = a.clone();
            future_to_promise(async move {
                match load_model(&a, &name, bytes.to_vec(), level).await {
                    Ok(()) => Ok(JsValue::TRUE),
                    Err(e) => {
                        show_error(&e.to_string());
                        Err(JsValue::from_str(&e.to_string()))
                    }
                }
            })
        },
    );
    set("loadModel", load.as_ref());
    load.forget();
    let a = app.clone();
    let frames = Closure::<dyn FnMut(u32) -> js_sys::Promise>::new(move |n: u32| {
        let a = a.clone();
        future_to_promise(async move {
            let mut times = Vec::new();
            for _ in 0..n.max(1) {
                draw_and_report(&a)
                    .await
                    .map_err(|e| JsValue::from_str(&e.to_string()))?;
                times.push(a.info.borrow().frame_ms);
            }
            Ok(times.iter().sum::<f64>().into())
        })
    });
    set("renderFrames", frames.as_ref());
    frames.forget();
    let a = app.clone();
    let stats = Closure::<dyn FnMut() -> JsValue>::new(move || stats_object(&a));
    set("stats", stats.as_ref());
    stats.forget();
    if let Some(w) = web_sys::window() {
        let _ = js_sys::Reflect::set(&w, &"ssbvb".into(), &api);
    }
}

fn stats_object(app: &App) -> JsValue {
    let info = app.info.borrow();
    let o = js_sys::Object::new();
    let put = |k: &str, v: JsValue| {
        let _ = js_sys::Reflect::set(&o, &k.into(), &v);
    };
    put("scene", info.scene.as_str().into());
    put("pipeline", info.pipeline.as_str().into());
    put("pipeline_reason", info.pipeline_reason.as_str().into());
    put("adapter", info.adapter.as_str().into());
    put("adapter_is_software", info.adapter_is_software.into());
    put("width", info.size.0.into());
    put("height", info.size.1.into());
    put("prepare_ms", info.prepare_ms.into());
    put("first_frame_ms", info.first_frame_ms.into());
    put("frame_ms", info.frame_ms.into());
    let passes = js_sys::Object::new();
    for p in &info.passes {
        let v = p.gpu_ms.map_or(JsValue::NULL, JsValue::from);
        let _ = js_sys::Reflect::set(&passes, &p.name.as_str().into(), &v);
    }
    put("passes_gpu_ms", passes.into());
    let warnings = js_sys::Array::new();
    for w in &info.warnings {
        warnings.push(&w.as_str().into());
    }
    put("warnings", warnings.into());
    let (updates, in_worker) = crate::worker_client::counts();
    put("progress_updates", updates.into());
    put("models_prepared_in_worker", in_worker.into());
    o.into()
}
