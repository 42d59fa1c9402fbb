//! `cargo xtask python-test` (run by `cargo xtask test`): the Python module built into a
//! virtual environment of its own (`target/python-venv`: maturin, numpy and pytest from
//! PyPI, the extension by `maturin develop` in the workspace's dev profile, so it reuses
//! the build the tests just made) and its pytest suite run against the `ssbvb` binary of
//! the same build. Prints how many Python tests passed.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

use crate::{web, web_test};

/// The Python packages the build and the suite need.
const PACKAGES: &[&str] = &["maturin>=1.9,<2", "numpy", "pytest"];

/// Runs the Python suite; `Ok(false)` when a test fails.
pub fn run(root: &Path) -> Result<bool> {
    let venv = web::target_dir(root).join("python-venv");
    let python = ensure_venv(&venv)?;
    let bin = web_test::native_binary(root)?;
    eprintln!("xtask: maturin develop -m crates/python/Cargo.toml");
    let built = Command::new(venv.join("bin/maturin"))
        .current_dir(root)
        .args(["develop", "--quiet", "-m", "crates/python/Cargo.toml"])
        .env("VIRTUAL_ENV", &venv)
        .status()
        .context("running maturin")?
        .success();
    if !built {
        bail!("maturin could not build the Python module");
    }
    eprintln!("xtask: pytest crates/python/tests");
    let mut cmd = Command::new(&python);
    cmd.current_dir(root)
        .args([
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "crates/python/tests",
        ])
        .env("SSBVB_BIN", &bin)
        .env("PYTHONDONTWRITEBYTECODE", "1");
    if std::env::var_os("WGPU_BACKEND").is_none() {
        cmd.env("WGPU_BACKEND", "vulkan");
    }
    crate::system::private_runtime_dir(&mut cmd);
    let out = cmd.output().context("running pytest")?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    print!("{stdout}");
    eprint!("{}", String::from_utf8_lossy(&out.stderr));
    let summary = stdout
        .lines()
        .rev()
        .find(|l| l.contains(" passed") || l.contains(" failed") || l.contains(" error"))
        .unwrap_or("no pytest summary");
    eprintln!(
        "xtask: python tests: {}",
        summary.trim_matches(|c| c == '=' || c == ' ')
    );
    Ok(out.status.success())
}

/// The virtual environment's Python, made (with `python3 -m venv`, or `SSBVB_PYTHON`'s)
/// and given [`PACKAGES`] when missing.
fn ensure_venv(venv: &Path) -> Result<PathBuf> {
    let python = venv.join("bin/python");
    if !python.is_file() {
        let base = std::env::var("SSBVB_PYTHON").unwrap_or_else(|_| "python3".into());
        eprintln!("xtask: {base} -m venv {}", venv.display());
        let ok = Command::new(&base)
            .args(["-m", "venv"])
            .arg(venv)
            .status()
            .with_context(|| format!("running {base} (Python 3.9+ with venv is needed)"))?
            .success();
        if !ok {
            bail!("{base} -m venv {} failed", venv.display());
        }
    }
    let have = Command::new(&python)
        .args(["-c", "import maturin, numpy, pytest"])
        .status()
        .is_ok_and(|s| s.success());
    if !have {
        eprintln!("xtask: pip install {}", PACKAGES.join(" "));
        let ok = Command::new(&python)
            .args(["-m", "pip", "install", "--quiet"])
            .args(PACKAGES)
            .status()
            .context("running pip")?
            .success();
        if !ok {
            bail!("pip install {} failed", PACKAGES.join(" "));
        }
    }
    Ok(python)
}
