//! The user's input: the orbit camera (a pointer drag, mouse or touch, a two-finger pinch,
//! the wheel; [`crate::gestures`]), a model chosen with the file input or dropped on the
//! canvas, and the frame loop that draws what changed.

use std::cell::RefCell;
use std::rc::Rc;

use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::{JsFuture, spawn_local};

use crate::app::{App, load_model, request_frames};
use crate::dom::{canvas, element, show_error};
use crate::gestures::{Gesture, Gestures};

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
    let gestures: Rc<RefCell<Gestures>> = Default::default();
    let (g, c) = (gestures.clone(), canvas.clone());
    listen(target, "pointerdown", move |e: web_sys::PointerEvent| {
        let _ = c.set_pointer_capture(e.pointer_id());
        let (x, y) = (f64::from(e.client_x()), f64::from(e.client_y()));
        g.borrow_mut().down(e.pointer_id(), x, y);
    });
    let (g, a) = (gestures.clone(), app.clone());
    listen(target, "pointermove", move |e: web_sys::PointerEvent| {
        let (x, y) = (f64::from(e.client_x()), f64::from(e.client_y()));
        let Some(gesture) = g.borrow_mut().moved(e.pointer_id(), x, y) else {
            return;
        };
        if let Ok(mut view) = a.view.try_borrow_mut() {
            match gesture {
                Gesture::Turn(dx, dy) => view.orbit.drag(dx, dy),
                Gesture::Zoom(units) => view.orbit.zoom(units),
            }
            view.touched = true;
            view.dirty = true;
        }
    });
    for kind in ["pointerup", "pointercancel"] {
        let g = gestures.clone();
        listen(target, kind, move |e: web_sys::PointerEvent| {
            g.borrow_mut().up(e.pointer_id())
        });
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
