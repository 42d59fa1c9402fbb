//! `cargo xtask web [--serve] [--port P]`: builds the browser page (crates/web for
//! wasm32-unknown-unknown, bound by wasm-bindgen) into `target/web/` with the assets it
//! fetches, and serves that folder on localhost (a secure context, as WebGPU needs).
//! The browser test is [`crate::web_test`].

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

/// The wasm-bindgen CLI must be the version of the `wasm-bindgen` crate the page links.
pub const WASM_BINDGEN_VERSION: &str = "0.2.130";

const TARGET: &str = "wasm32-unknown-unknown";

/// Runs `cargo xtask web ARGS`.
pub fn run(root: &Path, args: &[String]) -> Result<bool> {
    let mut serve = false;
    let mut port = 8080u16;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--serve" => serve = true,
            "--port" => {
                let v = it.next().context("--port needs a number")?;
                port = v
                    .parse()
                    .with_context(|| format!("--port: `{v}` is not a port number"))?;
            }
            "-h" | "--help" => {
                println!(
                    "cargo xtask web [--serve] [--port P]\n  builds the page into target/web/ \
                     (index.html, pkg/, assets/); with --serve, serves it at \
                     http://127.0.0.1:P/ (default 8080) until stopped"
                );
                return Ok(true);
            }
            other => bail!("web: unknown argument `{other}` (see `cargo xtask web --help`)"),
        }
    }
    let site = build(root)?;
    println!("web: wrote {}", site.join("index.html").display());
    if serve {
        let server = Server::start(&site, port)?;
        println!("web: serving {} at {}", site.display(), server.url());
        server.join();
    }
    Ok(true)
}

/// Builds the site into `target/web/` and returns that folder.
pub fn build(root: &Path) -> Result<PathBuf> {
    ensure_tools()?;
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    eprintln!("xtask: cargo build --release --target {TARGET} -p ssbvb-web");
    let ok = Command::new(&cargo)
        .current_dir(root)
        .args(["build", "--release", "--target", TARGET, "-p", "ssbvb-web"])
        .status()
        .context("running cargo build for the page")?
        .success();
    if !ok {
        bail!("the page did not build for {TARGET}");
    }
    let target_dir = target_dir(root);
    let site = target_dir.join("web");
    // Built beside the site and renamed in, so a failed build leaves the last site whole.
    let staging = target_dir.join("web.tmp");
    let _ = std::fs::remove_dir_all(&staging);
    std::fs::create_dir_all(&staging)?;
    let wasm = target_dir.join(TARGET).join("release/ssbvb_web.wasm");
    let ok = Command::new(wasm_bindgen())
        .args(["--target", "web", "--no-typescript", "--out-dir"])
        .arg(staging.join("pkg"))
        .arg(&wasm)
        .status()
        .context("running wasm-bindgen")?
        .success();
    if !ok {
        bail!("wasm-bindgen failed on {}", wasm.display());
    }
    for file in ["index.html", "worker.js"] {
        std::fs::copy(
            root.join("crates/web/static").join(file),
            staging.join(file),
        )?;
    }
    for dir in ["scenes", "pipelines", "models"] {
        copy_dir(
            &root.join("assets").join(dir),
            &staging.join("assets").join(dir),
        )?;
    }
    let _ = std::fs::remove_dir_all(&site);
    std::fs::rename(&staging, &site)
        .with_context(|| format!("moving the site to {}", site.display()))?;
    Ok(site)
}

/// The cargo target folder (`CARGO_TARGET_DIR` or `target/`).
pub fn target_dir(root: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from)
}

/// Copies `from` into `to` with its subfolders (pipelines include files of `shared/`).
fn copy_dir(from: &Path, to: &Path) -> Result<()> {
    std::fs::create_dir_all(to)?;
    for e in std::fs::read_dir(from).with_context(|| format!("reading {}", from.display()))? {
        let e = e?;
        let kind = e.file_type()?;
        if kind.is_file() {
            std::fs::copy(e.path(), to.join(e.file_name()))?;
        } else if kind.is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()))?;
        }
    }
    Ok(())
}

fn wasm_bindgen() -> PathBuf {
    let home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cargo")));
    match home.map(|h| h.join("bin/wasm-bindgen")) {
        Some(p) if p.is_file() => p,
        _ => PathBuf::from("wasm-bindgen"),
    }
}

/// Installs the wasm target (rustup) and the wasm-bindgen CLI of the right version
/// (`cargo install`, a few minutes once) when they are missing.
fn ensure_tools() -> Result<()> {
    let sysroot = Command::new("rustc")
        .args(["--print", "sysroot"])
        .output()
        .context("running rustc")?;
    let sysroot = PathBuf::from(String::from_utf8_lossy(&sysroot.stdout).trim());
    if !sysroot.join("lib/rustlib").join(TARGET).is_dir() {
        eprintln!("xtask: rustup target add {TARGET}");
        let ok = Command::new("rustup")
            .args(["target", "add", TARGET])
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            bail!("the {TARGET} target is missing: run `rustup target add {TARGET}`");
        }
    }
    let version = Command::new(wasm_bindgen())
        .arg("--version")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).to_string())
        .unwrap_or_default();
    if !version.contains(WASM_BINDGEN_VERSION) {
        eprintln!(
            "xtask: cargo install wasm-bindgen-cli --version {WASM_BINDGEN_VERSION} (found: {})",
            if version.is_empty() {
                "none"
            } else {
                version.trim()
            }
        );
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let ok = Command::new(cargo)
            .args([
                "install",
                "wasm-bindgen-cli",
                "--version",
                WASM_BINDGEN_VERSION,
            ])
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            bail!(
                "cannot install wasm-bindgen-cli {WASM_BINDGEN_VERSION}: run `cargo install \
                 wasm-bindgen-cli --version {WASM_BINDGEN_VERSION}`"
            );
        }
    }
    Ok(())
}

/// A static file server for the site on 127.0.0.1 (tiny_http, a thread per request).
pub struct Server {
    server: std::sync::Arc<tiny_http::Server>,
    port: u16,
    thread: std::thread::JoinHandle<()>,
}

impl Server {
    /// Serves `dir` on `port` (0: any free port).
    pub fn start(dir: &Path, port: u16) -> Result<Self> {
        let server = tiny_http::Server::http(("127.0.0.1", port))
            .map_err(|e| anyhow::anyhow!("cannot listen on 127.0.0.1:{port}: {e}"))?;
        let port = server.server_addr().to_ip().map_or(port, |a| a.port());
        let server = std::sync::Arc::new(server);
        let (s, dir) = (server.clone(), dir.to_path_buf());
        let thread = std::thread::spawn(move || {
            for request in s.incoming_requests() {
                let dir = dir.clone();
                std::thread::spawn(move || respond(&dir, request));
            }
        });
        Ok(Server {
            server,
            port,
            thread,
        })
    }

    /// The site's address.
    pub fn url(&self) -> String {
        format!("http://127.0.0.1:{}/", self.port)
    }

    /// Serves until the process ends.
    pub fn join(self) {
        let _ = self.thread.join();
    }

    /// Stops serving.
    pub fn stop(self) {
        self.server.unblock();
        let _ = self.thread.join();
    }
}

fn respond(dir: &Path, request: tiny_http::Request) {
    let path = request
        .url()
        .split(['?', '#'])
        .next()
        .unwrap_or("/")
        .to_string();
    let relative = path.trim_start_matches('/');
    let relative = if relative.is_empty() {
        "index.html"
    } else {
        relative
    };
    // Only plain names below the site: no `..`, no absolute paths.
    let safe = Path::new(relative)
        .components()
        .all(|c| matches!(c, std::path::Component::Normal(_)));
    let file = dir.join(relative);
    let response = match (safe, std::fs::read(&file)) {
        (true, Ok(bytes)) => {
            let kind = match file.extension().and_then(|e| e.to_str()) {
                Some("html") => "text/html; charset=utf-8",
                Some("js") => "text/javascript",
                Some("wasm") => "application/wasm",
                Some("ron" | "obj" | "txt" | "md") => "text/plain; charset=utf-8",
                _ => "application/octet-stream",
            };
            let header = tiny_http::Header::from_bytes("Content-Type", kind).expect("valid header");
            tiny_http::Response::from_data(bytes).with_header(header)
        }
        _ => tiny_http::Response::from_data(format!("not found: {path}").into_bytes())
            .with_status_code(404),
    };
    let _ = request.respond(response);
}
