//! `--limits webgpu` (WebGPU's default limits and no optional feature, what a browser
//! guarantees): `adapter` lists each adapter's verdict under those limits, and `render`
//! refuses up front a pipeline that needs more, naming the limit and who needs it, rather
//! than failing with a validation error mid-frame. `render --json` says which limits the
//! device was created with.

use super::{ssbvb, stdout_json, succeeded};

#[test]
fn webgpu_limits_are_checked_up_front_and_named() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    // The adapter's own limits: the default, and what `--json` says.
    let out = succeeded(
        ssbvb()
            .args([
                "render", "--size", "32x24", "--json", "--limits", "adapter", "-o",
            ])
            .arg(&png),
    );
    assert_eq!(stdout_json(&out)["limits"], "adapter");

    // `adapter --limits webgpu`: every adapter's verdict under WebGPU's defaults.
    let out = ssbvb()
        .args(["adapter", "--limits", "webgpu"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stdout.contains("under WebGPU's default limits"),
        "{stdout}{stderr}"
    );
    // Today's scene binds more storage buffers per stage than WebGPU's 8 (issue 34):
    // every adapter is refused, naming the limit, and the command says so.
    assert!(
        stdout.contains("lacks:") && stdout.contains("max_storage_buffers_per_shader_stage"),
        "{stdout}"
    );
    assert!(!out.status.success(), "{stdout}{stderr}");
    assert!(stderr.contains("--limits webgpu"), "{stderr}");

    std::fs::remove_file(&png).unwrap();
    let out = ssbvb()
        .args(["render", "--size", "32x24", "--limits", "webgpu", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("max_storage_buffers_per_shader_stage")
            && stderr.contains("under WebGPU's default limits (--limits webgpu)")
            && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(!png.exists());
}
