//! The page's start: URL parameters, the scene's files fetched and prepared, the device
//! and pipeline chosen, the first frame, then the controls and the frame loop. Every
//! failure ends in [`show_error`]: a message on the page and `document.title` starting
//! with `ssbvb error:`.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use ssbvb_gpu::{DeviceLimits, GpuContext, Verdict, wgpu};
use ssbvb_graph::ResolvedPipeline;
use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::spawn_local;

use crate::WebError;
use crate::app::{App, PageInfo, draw_and_report};
use crate::dom::{
    document, fetch_bytes, fetch_text, js_text, now_ms, show_error, status, window, yield_now,
};
use crate::params::PageParams;
use crate::present::Presenter;
use crate::scene_build;
use crate::view::View;

/// Entry point: runs the page and turns a failure or a panic into the page's message.
#[wasm_bindgen(start)]
pub fn start() {
    if web_sys::window().is_none() {
        // The voxelizing worker loads this module too: it has no page to run.
        return;
    }
    std::panic::set_hook(Box::new(|info| {
        let msg = format!("internal error (a bug; please report it): {info}");
        web_sys::console::error_1(&msg.clone().into());
        show_error(&msg);
    }));
    spawn_local(async {
        if let Err(e) = run().await {
            show_error(&e.to_string());
        }
    });
}

fn read_params() -> Result<PageParams, WebError> {
    let search = window().location().search().unwrap_or_default();
    let query = web_sys::UrlSearchParams::new_with_str(&search).map_err(|e| WebError::Param {
        key: "?".into(),
        message: js_text(&e),
    })?;
    let values: Vec<(&str, String)> = ["scene", "pipeline", "size"]
        .into_iter()
        .filter_map(|k| query.get(k).map(|v| (k, v)))
        .collect();
    PageParams::parse(values.iter().map(|(k, v)| (*k, v.as_str())))
}

/// Whether the page presents to its canvas: not in a headless browser, whose canvas
/// cannot present (`?present=1` or `0` decides otherwise).
fn presents() -> bool {
    let search = window().location().search().unwrap_or_default();
    if let Ok(q) = web_sys::UrlSearchParams::new_with_str(&search)
        && let Some(v) = q.get("present")
    {
        return v != "0";
    }
    let agent = window().navigator().user_agent().unwrap_or_default();
    !agent.contains("Headless")
}

async fn run() -> Result<(), WebError> {
    let params = read_params()?;
    crate::page_api::setup_controls(&params);
    let has_gpu = js_sys::Reflect::get(&window().navigator(), &"gpu".into())
        .is_ok_and(|g| !g.is_undefined() && !g.is_null());
    if !has_gpu {
        return Err(WebError::Gpu(
            "this browser has no WebGPU (navigator.gpu is missing): use a browser with WebGPU \
             on (Chrome or Edge 113+, Firefox 141+, Safari 26+), over https or localhost"
                .into(),
        ));
    }
    let scene_url = format!("assets/scenes/{}.ron", params.scene);
    status(&format!("loading {scene_url}"));
    let parsed = scene_build::parse_scene(&fetch_text(&scene_url).await?, &scene_url)?;
    let t_prepare = now_ms();
    let mut assets: Vec<Arc<ssbvb_voxel::asset::VoxelAsset>> = Vec::new();
    let mut done: Vec<((String, u32), Arc<ssbvb_voxel::asset::VoxelAsset>)> = Vec::new();
    for (model, level) in parsed.models() {
        if let Some((_, a)) = done.iter().find(|(k, _)| *k == (model.clone(), level)) {
            assets.push(a.clone());
            continue;
        }
        let url = format!("assets/scenes/{model}");
        status(&format!("loading {model}"));
        let bytes = fetch_bytes(&url).await?;
        let asset = Arc::new(crate::worker_client::prepare(&model, bytes, level).await?);
        done.push(((model, level), asset.clone()));
        assets.push(asset);
    }
    let prepare_ms = now_ms() - t_prepare;
    status("opening the GPU");
    let (instance, adapter) = adapter().await?;
    let (pipeline_name, pipeline, verdict, reason) = choose_pipeline(&params, &adapter).await?;
    let adapter_is_cpu = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
    let ctx = GpuContext::from_adapter_async(
        instance.clone(),
        adapter,
        verdict.fallback_notes(),
        DeviceLimits::Adapter,
    )
    .await
    .map_err(|e| WebError::Gpu(e.to_string()))?;
    let canvas = crate::dom::canvas();
    let size = params
        .size
        .unwrap_or_else(|| crate::dom::canvas_size(&canvas));
    canvas.set_width(size.0);
    canvas.set_height(size.1);
    status("uploading the scene");
    yield_now().await;
    let mut view = View::open(
        &ctx,
        parsed.build(assets)?,
        parsed.camera(),
        pipeline.clone(),
        size,
        None,
    )?;
    if presents() {
        let surface = instance
            .create_surface(wgpu::SurfaceTarget::Canvas(canvas.clone()))
            .map_err(|e| WebError::Gpu(format!("cannot draw into the canvas: {e}")))?;
        view.presenter = Some(Presenter::new(
            &ctx,
            surface,
            &view.renderer.output().texture,
        )?);
    }
    let adapter_name = ctx.report().to_string();
    let app = Rc::new(App {
        ctx,
        view: RefCell::new(view),
        info: RefCell::new(PageInfo {
            scene: params.scene.clone(),
            pipeline: pipeline_name.clone(),
            pipeline_reason: reason,
            adapter: adapter_name,
            adapter_is_software: adapter_is_cpu,
            size,
            prepare_ms,
            warnings: crate::worker_client::take_warnings(),
            ..Default::default()
        }),
        pipeline,
        follows_canvas: params.size.is_none(),
        drawing: Default::default(),
    });
    draw_and_report(&app).await?;
    app.info.borrow_mut().first_frame_ms = now_ms();
    crate::page_api::install(app.clone());
    crate::page_input::install(app.clone());
    status("");
    document().set_title(&format!(
        "ssbvb ready: {} with {} at {}x{}",
        params.scene, pipeline_name, size.0, size.1
    ));
    Ok(())
}

/// The browser's WebGPU adapter (a fallback adapter, such as a software one, when it is
/// the only one).
async fn adapter() -> Result<(wgpu::Instance, wgpu::Adapter), WebError> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::BROWSER_WEBGPU;
    let instance = wgpu::Instance::new(desc);
    for fallback in [false, true] {
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: fallback,
            compatible_surface: None,
            apply_limit_buckets: false,
        };
        if let Ok(a) = instance.request_adapter(&options).await {
            return Ok((instance, a));
        }
    }
    Err(WebError::Gpu(
        "the browser gave no WebGPU adapter: WebGPU may be off or the GPU blocked \
         (chrome://gpu says why; Chromium on Linux needs --enable-unsafe-webgpu)"
            .into(),
    ))
}

/// The pipeline the URL names, else the first default SSBVB form the adapter can run
/// (the rule of `ssbvb render`): its stem, the pipeline, the adapter's verdict and why.
async fn choose_pipeline(
    params: &PageParams,
    adapter: &wgpu::Adapter,
) -> Result<(String, ResolvedPipeline, Verdict, String), WebError> {
    let cpu = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
    // The rule of the engine's form table: its forms in order, CPU-only ones on a CPU.
    let rule = ssbvb_engine::forms::rule_forms();
    let cpu_only: Vec<&str> = rule
        .iter()
        .filter(|f| f.cpu_only)
        .map(|f| f.stem())
        .collect();
    let candidates: Vec<&str> = match &params.pipeline {
        Some(p) => vec![p.as_str()],
        None => rule
            .iter()
            .filter(|f| cpu || !f.cpu_only)
            .map(|f| f.stem())
            .collect(),
    };
    let mut refused = Vec::new();
    for name in candidates {
        let url = format!("assets/pipelines/{name}.ron");
        let resolved = crate::dom::fetch_pipeline(&url).await?;
        let verdict =
            ssbvb_passes::pipeline_requirements(&resolved).check_under(adapter, &adapter.limits());
        if verdict.fits() {
            let reason = if params.pipeline.is_some() {
                "named in the URL".to_string()
            } else if cpu {
                "the fastest SSBVB form this CPU adapter can run (the rule of `ssbvb render`)"
                    .to_string()
            } else {
                format!(
                    "the fastest SSBVB form this adapter can run (the rule of `ssbvb render`; \
                     {} only on a CPU adapter)",
                    cpu_only.join(", ")
                )
            };
            return Ok((name.to_string(), resolved, verdict, reason));
        }
        refused.push(format!("{name}: {}", verdict.missing.join("; ")));
    }
    Err(WebError::Gpu(format!(
        "this browser's adapter ({}) cannot run the pipeline: {}",
        adapter.get_info().name,
        refused.join(" | ")
    )))
}
