//! The user's input: the orbit camera (pointer drag, mouse or touch, and the wheel), a
//! model chosen with the file input or dropped on the canvas, and the frame loop that
//! draws what changed.

use std::rc::Rc;

use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::{JsFuture, spawn_local};

use crate::app::{App, load_model, request_frames};
use crate::dom::{canvas, element, show_error};

fn listen<E: JsCast + wasm_bindgen::convert::FromWasmAbi + 'static>(
    target: &web_sys::EventTarget,
    kind: &str,
    f: impl FnMut(E) + 'static,
) {
    let f = Closure::<dyn FnMut(E)>::new(f);
    let _ = target.add_event_listener_with_callback(kind, f.as_ref().unchecked_ref());
    f.forget();
}

/// Wires the canvas, the file input and the frame loop to `app`.
pub fn install(app: Rc<App>) {
    let canvas = canvas();
    let target: &web_sys::EventTarget = canvas.as_ref();
    let last: Rc<std::cell::Cell<Option<(i32, i32)>>> = Default::default();
    let (l, c) = (last.clone(), canvas.clone());
    listen(target, "pointerdown", move |e: web_sys::PointerEvent| {
        let _ = c.set_pointer_capture(e.pointer_id());
        l.set(Some((e.client_x(), e.client_y())));
    });
    let (l, a) = (last.clone(), app.clone());
    listen(target, "pointermove", move |e: web_sys::PointerEvent| {
        let Some((x, y)) = l.get() else {
            return;
        };
        let (nx, ny) = (e.client_x(), e.client_y());
        l.set(Some((nx, ny)));
        if let Ok(mut view) = a.view.try_borrow_mut() {
            view.orbit.drag(f64::from(nx - x), f64::from(ny - y));
            view.touched = true;
            view.dirty = true;
        }
    });
    for kind in ["pointerup", "pointercancel"] {
        let l = last.clone();
        listen(target, kind, move |_: web_sys::PointerEvent| l.set(None));
    }
    let a = app.clone();
    listen(target, "wheel", move |e: web_sys::WheelEvent| {
        e.prevent_default();
        if let Ok(mut view) = a.view.try_borrow_mut() {
            view.orbit.zoom(e.delta_y());
            view.touched = true;
            view.dirty = true;
        }
    });
    listen(target, "dragover", |e: web_sys::DragEvent| {
        e.prevent_default()
    });
    let a = app.clone();
    listen(target, "drop", move |e: web_sys::DragEvent| {
        e.prevent_default();
        if let Some(file) = e
            .data_transfer()
            .and_then(|d| d.files())
            .and_then(|f| f.get(0))
        {
            load_file(a.clone(), file);
        }
    });
    if let Some(input) = element::<web_sys::HtmlInputElement>("file") {
        let (a, i) = (app.clone(), input.clone());
        listen(input.as_ref(), "change", move |_: web_sys::Event| {
            if let Some(file) = i.files().and_then(|f| f.get(0)) {
                load_file(a.clone(), file);
            }
        });
    }
    request_frames(app);
}

/// The level the page's level input asks for.
fn chosen_level() -> u32 {
    element::<web_sys::HtmlInputElement>("level")
        .and_then(|i| i.value().trim().parse().ok())
        .unwrap_or(8)
}

fn load_file(app: Rc<App>, file: web_sys::File) {
    spawn_local(async move {
        let name = file.name();
        let bytes = match JsFuture::from(file.array_buffer()).await {
            Ok(b) => js_sys::Uint8Array::new(&b).to_vec(),
            Err(e) => {
                show_error(&format!("{name}: cannot read the file: {e:?}"));
                return;
            }
        };
        if let Err(e) = load_model(&app, &name, bytes, chosen_level()).await {
            show_error(&e.to_string());
        }
    });
}
