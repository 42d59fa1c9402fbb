//! What a headless program on Linux does before its first device: keep Mesa's window-system
//! probe quiet where no display runtime folder exists.

/// Headless programs still load Mesa's Vulkan window-system code, which asks
/// libwayland for `XDG_RUNTIME_DIR` and prints `error: XDG_RUNTIME_DIR is invalid or not set`
/// per device when it is unset (headless machines, containers). Point it at a private empty
/// folder instead: no Wayland socket is found there, silently, and nothing else reads it.
///
/// # Safety
///
/// It sets an environment variable: call it first thing in `main`, before any other
/// thread exists.
pub unsafe fn quiet_window_system_probe() {
    if !cfg!(target_os = "linux") {
        return;
    }
    let valid = std::env::var_os("XDG_RUNTIME_DIR")
        .filter(|d| !d.is_empty())
        .is_some_and(|d| std::path::Path::new(&d).is_dir());
    if valid {
        return;
    }
    // One folder per user (not per process: nothing accumulates in the temp folder).
    #[cfg(unix)]
    let user = {
        use std::os::unix::fs::MetadataExt;
        std::fs::metadata("/proc/self")
            .map(|m| m.uid())
            .unwrap_or(0)
    };
    #[cfg(not(unix))]
    let user = 0;
    let dir = std::env::temp_dir().join(format!("ssbvb-xdg-runtime-{user}"));
    if std::fs::create_dir_all(&dir).is_err() {
        return;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
    }
    // SAFETY: the caller's promise: no other thread exists yet, so nothing reads the
    // environment concurrently.
    unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
}
