//! Project tasks: `cargo xtask validate-shaders [--dir DIR]`, `cargo xtask test [ARGS]`,
//! `cargo xtask imports`, `cargo xtask fuzz [TARGET ...] [--seconds N]`,
//! `cargo xtask mutate-shaders [FILE ...] [--tests FILTER] [--report FILE]`,
//! `cargo xtask gpu-bench [--bin PATH] [--out DIR] ...`.

mod fuzz;
mod gpu_bench;
mod imports;
mod layout_check;
mod mutate;
mod python_test;
mod shaders;
mod standalone;
mod system;
mod web;
mod web_test;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use anyhow::{Context, Result, bail};

const USAGE: &str = "usage:
  cargo xtask validate-shaders [--dir DIR]   parse and validate every .wgsl under shaders/ (or DIR)
  cargo xtask test [CARGO TEST ARGS]         make sure a GPU adapter exists, check formatting, check that
                                             no tracked file refers outside the repository, check the
                                             import circles (see imports), validate shaders, run
                                             clippy (-D warnings), build the docs (warnings denied),
                                             run all workspace tests, the web page in headless
                                             Chromium (web-test) and fuzz every parser for 20 s
  cargo xtask imports [--root DIR]           the files of each crate as an import graph: files, arrows,
                                             floors and circles (files importing each other); fails
                                             when crates/passes, crates/gpu or crates/gpu-build has one
  cargo xtask fuzz [TARGET ...] [--seconds N] [--runs N] [--artifacts DIR] [--report FILE]
                                             coverage-guided fuzzing of every parser on stable
                                             (see `cargo xtask fuzz --help`)
  cargo xtask mutate-shaders [FILE ...] [--tests FILTER] [--report FILE] [--timeout S] [--lines A-B]
                             [--every N] [--list] [--test-binary PATH]
                                             mutation testing of the WGSL shaders against the GPU tests
                                             that exercise them (see `cargo xtask mutate-shaders --help`)
  cargo xtask gpu-bench [--bin PATH] [--out DIR] [--frames N] [--skip-paper] [--allow-software] [--dry-run]
                                             on a machine with a GPU: the per-pass breakdown of every
                                             SSBVB form and ray caster, then the paper preset, into
                                             docs/bench/<gpu>/ (see `cargo xtask gpu-bench --help`)
  cargo xtask web [--serve] [--port P]       build the browser page into target/web/ (wasm32 + WebGPU);
                                             with --serve, serve it at http://127.0.0.1:P/
  cargo xtask web-test                       build the page and check it in headless Chromium against
                                             native renders (part of `cargo xtask test`)
  cargo xtask python-test                    build the Python module into target/python-venv (maturin) and
                                             run its pytest suite (part of `cargo xtask test`)";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("validate-shaders") => validate_shaders(&args[1..]),
        Some("test") => test(&args[1..]),
        Some("fuzz") => fuzz::run(&workspace_root(), &args[1..]),
        Some("imports") => imports::run(&workspace_root(), &args[1..]),
        Some("mutate-shaders") => mutate::run(&workspace_root(), &args[1..]),
        Some("gpu-bench") => gpu_bench::run(&run_root(), &args[1..]),
        Some("web") => web::run(&workspace_root(), &args[1..]),
        Some("web-test") => web_test::run(&workspace_root()),
        Some("python-test") => python_test::run(&workspace_root()),
        Some("-h" | "--help") | None => {
            println!("{USAGE}");
            Ok(true)
        }
        Some(other) => {
            eprintln!("unknown task `{other}`\n{USAGE}");
            Ok(false)
        }
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// The checkout a task runs in: the current folder where it is one (an xtask binary carried
/// to another machine), else the one this xtask was built from.
fn run_root() -> PathBuf {
    std::env::current_dir()
        .ok()
        .filter(|d| d.join("assets/scenes/default.ron").is_file())
        .unwrap_or_else(workspace_root)
}

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

fn validate_shaders(args: &[String]) -> Result<bool> {
    let dir = match args {
        [] => workspace_root().join("shaders"),
        [flag, dir] if flag == "--dir" => PathBuf::from(dir),
        _ => bail!("validate-shaders takes only `--dir DIR`\n{USAGE}"),
    };
    let report = shaders::validate_dir(&dir, &shaders::registered())?;
    for line in &report.errors {
        eprintln!("{line}");
    }
    println!(
        "validate-shaders: {} file(s) under {}, {} registered pass kind(s) checked, {} error(s)",
        report.files,
        dir.display(),
        report.kinds_checked,
        report.errors.len()
    );
    Ok(report.errors.is_empty())
}

/// Whether a Vulkan driver (ICD) is installed, looking where the Vulkan loader looks.
fn vulkan_icd_present() -> bool {
    let mut dirs = vec![
        PathBuf::from("/usr/share/vulkan/icd.d"),
        PathBuf::from("/etc/vulkan/icd.d"),
        PathBuf::from("/usr/local/share/vulkan/icd.d"),
    ];
    if let Ok(files) =
        std::env::var("VK_ICD_FILENAMES").or_else(|_| std::env::var("VK_DRIVER_FILES"))
    {
        return files.split(':').any(|f| Path::new(f).exists());
    }
    if let Ok(xdg) = std::env::var("XDG_DATA_DIRS") {
        dirs.extend(xdg.split(':').map(|d| Path::new(d).join("vulkan/icd.d")));
    }
    dirs.iter().any(|d| {
        std::fs::read_dir(d)
            .map(|rd| {
                rd.flatten()
                    .any(|e| e.path().extension().is_some_and(|x| x == "json"))
            })
            .unwrap_or(false)
    })
}

/// Whether Mesa's EGL (the GL backend's test) is installed.
fn mesa_egl_present() -> bool {
    [
        "/usr/lib/x86_64-linux-gnu",
        "/usr/lib/aarch64-linux-gnu",
        "/usr/lib64",
        "/usr/lib",
    ]
    .iter()
    .any(|d| Path::new(d).join("libEGL_mesa.so.0").exists())
}

/// Whether `xvfb-run` (the `ssbvb view` test's virtual display) is on the PATH.
fn xvfb_present() -> bool {
    std::env::var_os("PATH")
        .is_some_and(|p| std::env::split_paths(&p).any(|d| d.join("xvfb-run").is_file()))
}

/// Packages the tests need on Debian/Ubuntu: Mesa's lavapipe and GL driver, and Xvfb with
/// the X libraries winit loads at run time for the `ssbvb view` test.
const APT_PACKAGES: &[&str] = &[
    "mesa-vulkan-drivers",
    "libvulkan1",
    "xvfb",
    "libxkbcommon-x11-0",
    "libx11-xcb1",
    "libxcursor1",
    "libxi6",
    "libxrandr2",
    // Mesa's GL driver (EGL, GLES) for the GL backend's test.
    "libegl1",
    "libegl-mesa0",
    "libgles2",
    "libgl1-mesa-dri",
    // libFuzzer (C++) for the fuzz smoke.
    "g++",
];

/// Makes sure a Vulkan adapter can exist: on Linux without a Vulkan driver (or without
/// Xvfb), installs Mesa's lavapipe and Xvfb when running as root with apt, else says what
/// to install (a missing Xvfb is reported by the viewer test itself).
fn ensure_adapter() -> Result<()> {
    if !cfg!(target_os = "linux") || (vulkan_icd_present() && xvfb_present() && mesa_egl_present())
    {
        return Ok(());
    }
    let apt = Path::new("/usr/bin/apt-get").exists();
    if apt && system::is_root() {
        eprintln!("xtask: no Vulkan driver or no Xvfb found; installing Mesa's lavapipe and Xvfb");
        let ok = |c: &mut Command| c.status().map(|s| s.success()).unwrap_or(false);
        let env = [("DEBIAN_FRONTEND", "noninteractive")];
        if !ok(Command::new("apt-get").args(["update", "-qq"]).envs(env)) {
            eprintln!("xtask: apt-get update failed; trying the install anyway");
        }
        if !ok(Command::new("apt-get")
            .args(["install", "-y", "-qq"])
            .args(APT_PACKAGES)
            .envs(env))
        {
            bail!("apt-get install {} failed", APT_PACKAGES.join(" "));
        }
        if vulkan_icd_present() {
            return Ok(());
        }
        bail!("mesa-vulkan-drivers installed but no Vulkan ICD file appeared");
    }
    if vulkan_icd_present() {
        // Only Xvfb is missing: the viewer test fails and says to install it.
        return Ok(());
    }
    bail!(
        "no Vulkan driver found and cannot install one here (needs root and apt). Install Mesa's \
         software Vulkan driver: `sudo apt-get install -y mesa-vulkan-drivers libvulkan1` \
         (Debian/Ubuntu), `dnf install mesa-vulkan-drivers` (Fedora), or a GPU driver"
    )
}

fn test(extra: &[String]) -> Result<bool> {
    ensure_adapter()?;
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let root = workspace_root();
    let run = |args: &[&str]| -> Result<bool> {
        eprintln!("xtask: cargo {}", args.join(" "));
        Ok(Command::new(&cargo)
            .current_dir(&root)
            .args(args)
            .status()
            .context("running cargo")?
            .success())
    };
    if !run(&["fmt", "--all", "--check"])? {
        eprintln!("xtask: formatting differs; run `cargo fmt --all`");
        return Ok(false);
    }
    if !standalone::check(&root)? {
        return Ok(false);
    }
    if !imports::run(&root, &[])? {
        return Ok(false);
    }
    if !validate_shaders(&[])? {
        return Ok(false);
    }
    if !run(&[
        "clippy",
        "--workspace",
        "--all-targets",
        "--quiet",
        "--",
        "-D",
        "warnings",
    ])? {
        return Ok(false);
    }
    // Docs that cannot rot: broken intra-doc links and malformed docs fail the run.
    eprintln!("xtask: cargo doc --workspace --no-deps (RUSTDOCFLAGS=-D warnings)");
    let doc_ok = Command::new(&cargo)
        .current_dir(&root)
        .args(["doc", "--workspace", "--no-deps", "--quiet"])
        .env("RUSTDOCFLAGS", "-D warnings")
        .status()
        .context("running cargo doc")?
        .success();
    if !doc_ok {
        eprintln!("xtask: the documentation has warnings; see above");
        return Ok(false);
    }
    let mut cmd = Command::new(&cargo);
    cmd.current_dir(workspace_root())
        .args(["test", "--workspace"])
        .args(extra);
    // One backend for headless tests: with all of them the GL path logs EGL errors and
    // finds a second llvmpipe adapter.
    if std::env::var_os("WGPU_BACKEND").is_none() {
        cmd.env("WGPU_BACKEND", "vulkan");
    }
    system::private_runtime_dir(&mut cmd);
    if !cmd.status().context("running cargo test")?.success() {
        return Ok(false);
    }
    // The core frame tests again on the GL backend (Mesa's llvmpipe as OpenGL ES), which the
    // run above does not use.
    if extra.is_empty() {
        let mut gl = Command::new(&cargo);
        gl.current_dir(&root)
            .args([
                "test",
                "-p",
                "ssbvb-tests",
                "--test",
                "gpu",
                "core_frames::",
            ])
            .env("WGPU_BACKEND", "gl");
        system::private_runtime_dir(&mut gl);
        eprintln!("xtask: the core frame tests on GL (WGPU_BACKEND=gl)");
        if !gl.status().context("running cargo test on GL")?.success() {
            eprintln!("xtask: the core frame tests failed on the GL backend");
            return Ok(false);
        }
    }
    // The Python module's suite (numpy in, pixels out) against the CLI.
    if extra.is_empty() {
        eprintln!("xtask: the Python module (cargo xtask python-test)");
        if !python_test::run(&root)? {
            eprintln!("xtask: the Python tests failed");
            return Ok(false);
        }
    }
    // The web page in headless Chromium against native renders.
    if extra.is_empty() {
        eprintln!("xtask: the web page in headless Chromium (cargo xtask web-test)");
        if !web_test::run(&root)? {
            eprintln!("xtask: the web page's browser test failed");
            return Ok(false);
        }
    }
    // A short fuzz smoke, so a parser regression shows on the next submission (the
    // campaign's long runs are `cargo xtask fuzz --seconds N`). Skipped when the test
    // run was narrowed by arguments.
    if extra.is_empty() {
        let smoke = [String::from("--seconds"), String::from(FUZZ_SMOKE_SECONDS)];
        return fuzz::run(&root, &smoke);
    }
    Ok(true)
}

/// Seconds per fuzz target in `cargo xtask test`.
const FUZZ_SMOKE_SECONDS: &str = "20";
