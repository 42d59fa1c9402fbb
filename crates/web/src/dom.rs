//! The page's DOM and browser plumbing: elements, the status line and message, fetching
//! files, yielding to the browser, and waiting for the GPU.

use ssbvb_gpu::GpuContext;
use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::JsFuture;

use crate::WebError;
use crate::params::MAX_EDGE;

/// The page's window.
pub fn window() -> web_sys::Window {
    web_sys::window().expect("a page has a window")
}

/// The page's document.
pub fn document() -> web_sys::Document {
    window().document().expect("a page has a document")
}

/// Milliseconds since the page started.
pub fn now_ms() -> f64 {
    window().performance().map_or(0.0, |p| p.now())
}

/// Shows `text` in the page's status line.
pub fn status(text: &str) {
    if let Some(e) = document().get_element_by_id("status") {
        e.set_text_content(Some(text));
    }
}

/// Shows a failure on the page and in its title.
pub fn show_error(message: &str) {
    if let Some(e) = document().get_element_by_id("message") {
        e.set_text_content(Some(message));
        let _ = e.set_attribute("class", "error");
    }
    status("");
    document().set_title(&format!("ssbvb error: {message}"));
}

/// Clears the page's message.
pub fn clear_error() {
    if let Some(e) = document().get_element_by_id("message") {
        e.set_text_content(None);
        let _ = e.set_attribute("class", "");
    }
}

/// Lets the browser run (paint the status, handle input) before long work goes on.
pub async fn yield_now() {
    let promise = js_sys::Promise::new(&mut |resolve, _| {
        let _ = window().set_timeout_with_callback_and_timeout_and_arguments_0(&resolve, 0);
    });
    let _ = JsFuture::from(promise).await;
}

/// Resolves when the GPU has done every frame submitted so far.
pub async fn gpu_done(ctx: &GpuContext) {
    let (tx, rx) = futures_channel::oneshot::channel();
    ctx.queue.on_submitted_work_done(move || {
        let _ = tx.send(());
    });
    let _ = rx.await;
}

/// A JavaScript value (an error, a string) as text.
pub fn js_text(v: &JsValue) -> String {
    v.as_string()
        .or_else(|| {
            v.dyn_ref::<js_sys::Error>()
                .map(|e| String::from(e.message()))
        })
        .unwrap_or_else(|| format!("{v:?}"))
}

/// The bytes of `url` (relative to the page).
pub async fn fetch_bytes(url: &str) -> Result<Vec<u8>, WebError> {
    let failed = |message: String| WebError::Fetch {
        url: url.to_string(),
        message,
    };
    let response = JsFuture::from(window().fetch_with_str(url))
        .await
        .map_err(|e| failed(js_text(&e)))?;
    let response: web_sys::Response = response.unchecked_into();
    if !response.ok() {
        return Err(failed(format!(
            "HTTP {} {}",
            response.status(),
            response.status_text()
        )));
    }
    let buffer = JsFuture::from(response.array_buffer().map_err(|e| failed(js_text(&e)))?)
        .await
        .map_err(|e| failed(js_text(&e)))?;
    Ok(js_sys::Uint8Array::new(&buffer).to_vec())
}

/// The text of `url` (UTF-8).
pub async fn fetch_text(url: &str) -> Result<String, WebError> {
    String::from_utf8(fetch_bytes(url).await?).map_err(|e| WebError::Fetch {
        url: url.to_string(),
        message: format!("not UTF-8 text: {e}"),
    })
}

/// The pipeline file at `url`, resolved with the files it includes (fetched first, each
/// once, relative to the file that names it).
pub async fn fetch_pipeline(url: &str) -> Result<ssbvb_graph::ResolvedPipeline, WebError> {
    let text = fetch_text(url).await?;
    let mut fetched = std::collections::HashMap::new();
    let mut failed = std::collections::HashMap::new();
    let mut pending: Vec<(String, String)> = ssbvb_graph::include::includes_of(&text)
        .into_iter()
        .map(|n| (url.to_string(), n))
        .collect();
    while let Some((from, name)) = pending.pop() {
        let path = ssbvb_graph::include::include_path(&from, &name);
        if fetched.contains_key(&path) || failed.contains_key(&path) {
            continue;
        }
        // A failed fetch is reported by the resolver, at the line that names it.
        let included = match fetch_text(&path).await {
            Ok(t) => t,
            Err(e) => {
                failed.insert(path, e.to_string());
                continue;
            }
        };
        for n in ssbvb_graph::include::includes_of(&included) {
            pending.push((path.clone(), n));
        }
        fetched.insert(path, included);
    }
    let read = |p: &str| {
        fetched
            .get(p)
            .cloned()
            .ok_or_else(|| "not found".to_string())
    };
    ssbvb_graph::resolve_str_with(&text, url, &read).map_err(|e| WebError::Pipeline(e.to_string()))
}

/// The element `id`, as `T`.
pub fn element<T: JsCast>(id: &str) -> Option<T> {
    document()
        .get_element_by_id(id)
        .and_then(|e| e.dyn_into::<T>().ok())
}

/// The page's canvas (`#view`).
pub fn canvas() -> web_sys::HtmlCanvasElement {
    element("view").expect("index.html has a canvas#view")
}

/// The canvas's size on screen in device pixels, at most [`MAX_EDGE`] a side.
pub fn canvas_size(canvas: &web_sys::HtmlCanvasElement) -> (u32, u32) {
    let ratio = web_sys::window().map_or(1.0, |w| w.device_pixel_ratio());
    let side = |css: i32| ((f64::from(css.max(1)) * ratio).round() as u32).clamp(1, MAX_EDGE);
    (side(canvas.client_width()), side(canvas.client_height()))
}
