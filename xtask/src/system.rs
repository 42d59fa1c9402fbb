//! Facts about the machine the tasks run on.

use std::process::Command;

/// Whether this process runs as root (then missing system packages can be installed).
pub fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

/// Mesa's Vulkan WSI probes XDG_RUNTIME_DIR and prints an error per device when it is unset
/// (typical in CI containers): gives `cmd` a private folder then.
pub fn private_runtime_dir(cmd: &mut Command) {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some() {
        return;
    }
    let dir = std::env::temp_dir().join("ssbvb-xdg-runtime");
    if std::fs::create_dir_all(&dir).is_ok() {
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
        }
        cmd.env("XDG_RUNTIME_DIR", &dir);
    }
}
