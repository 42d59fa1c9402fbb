//! ssbvb in the browser: the page that `cargo xtask web` builds (wasm32-unknown-unknown,
//! wgpu's WebGPU backend, bound to JavaScript by wasm-bindgen).
//!
//! The page fetches a bundled scene, its models and a pipeline over HTTP, prepares the
//! models in the page (the same loaders and voxelizer as the CLI), draws the frame into the
//! pipeline's output texture with the same passes as `ssbvb render`, and presents it to a
//! canvas. `window.ssbvb` is its API for scripts and tests (`readPixels`, `loadModel`,
//! `stats`, `renderFrames`); `document.title` says when the first frame is done (`ssbvb
//! ready…`) or what failed (`ssbvb error: …`). What differs from the native renderer
//! (one thread, no files, WebGPU's limits, timestamps) is in `docs/architecture.md`.
//!
//! Models are prepared in a Web Worker (`static/worker.js`, the same module) so the page
//! stays responsive and shows the voxelizer's progress; the asset comes back as bytes
//! ([`asset_bytes`]).
//!
//! Natively the crate is only its testable parts: the URL parameters ([`params`]), the
//! scene made from fetched bytes ([`scene_build`]) and the asset's bytes
//! ([`asset_bytes`]).

pub mod asset_bytes;
pub mod gestures;
pub mod params;
pub mod scene_build;

#[cfg(target_arch = "wasm32")]
mod app;
#[cfg(target_arch = "wasm32")]
mod dom;
#[cfg(target_arch = "wasm32")]
mod page;
#[cfg(target_arch = "wasm32")]
mod page_api;
#[cfg(target_arch = "wasm32")]
mod page_input;
#[cfg(target_arch = "wasm32")]
mod present;
#[cfg(target_arch = "wasm32")]
mod view;
#[cfg(target_arch = "wasm32")]
mod worker;
#[cfg(target_arch = "wasm32")]
mod worker_client;

/// What went wrong, as the page shows it.
#[derive(Debug, thiserror::Error)]
pub enum WebError {
    /// A URL parameter the page cannot use.
    #[error("URL parameter {key}: {message}")]
    Param {
        /// The parameter.
        key: String,
        /// Why.
        message: String,
    },
    /// A scene file that cannot be drawn here.
    #[error("{0}")]
    Scene(String),
    /// A model file that cannot be loaded or prepared.
    #[error("{name}: {message}")]
    Model {
        /// The file's name.
        name: String,
        /// Why.
        message: String,
    },
    /// A file the page could not fetch.
    #[error("cannot fetch {url}: {message}")]
    Fetch {
        /// What was asked for.
        url: String,
        /// Why.
        message: String,
    },
    /// No WebGPU, no adapter, or an adapter without what the pipeline needs.
    #[error("{0}")]
    Gpu(String),
    /// A pipeline file that does not resolve.
    #[error("{0}")]
    Pipeline(String),
}

#[cfg(test)]
mod tests {
    /// The canvas blit's shader parses and validates (the browser compiles it only where
    /// it presents, which a headless test browser does not).
    #[test]
    fn the_canvas_blit_shader_validates() {
        let module = naga::front::wgsl::parse_str(include_str!("present.wgsl")).unwrap();
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .unwrap();
        for entry in ["vs_main", "fs_main"] {
            assert!(
                module.entry_points.iter().any(|e| e.name == entry),
                "{entry}"
            );
        }
    }
}
