//! Whether a window can be opened at all, and the message when it cannot.

/// What to say when there is no display: where to look and what to run instead.
pub fn no_display_message(why: &str) -> String {
    format!("ssbvb view needs a display ({why}); use `ssbvb render` to write an image instead")
}

/// On Linux and the BSDs (X11 / Wayland), `Err` with the reason when neither `DISPLAY` nor
/// `WAYLAND_DISPLAY` is set: winit would fail later with a less helpful message. Other
/// systems always have a window server.
pub fn check_display_env() -> Result<(), String> {
    if cfg!(all(
        unix,
        not(target_os = "macos"),
        not(target_os = "android")
    )) {
        let set = |v: &str| std::env::var_os(v).is_some_and(|s| !s.is_empty());
        if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
            return Err(no_display_message("DISPLAY and WAYLAND_DISPLAY are unset"));
        }
    }
    Ok(())
}
