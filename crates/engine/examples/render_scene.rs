//! Renders a scene file to a PNG through the engine's API, as `ssbvb render SCENE --size
//! WxH -o OUT.png` does: `cargo run --release -p ssbvb-engine --example render_scene --
//! SCENE OUT.png WxH`.

use std::path::PathBuf;
use std::process::ExitCode;

use ssbvb_engine::{Content, Engine, RenderOptions};
use ssbvb_voxel::progress::NoProgress;

fn main() -> ExitCode {
    // SAFETY: first thing in `main`, before any other thread exists.
    unsafe { ssbvb_engine::platform::quiet_window_system_probe() };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, out, size] = args.as_slice() else {
        eprintln!("usage: render_scene SCENE OUT.png WxH");
        return ExitCode::FAILURE;
    };
    match run(scene.into(), out.into(), size) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(scene: PathBuf, out: PathBuf, size: &str) -> Result<(), Box<dyn std::error::Error>> {
    let parse = |s: &str| s.trim().parse::<u32>().ok().filter(|&v| v > 0);
    let size = size
        .split_once('x')
        .and_then(|(w, h)| Some((parse(w)?, parse(h)?)))
        .ok_or_else(|| format!("size `{size}`: expected WxH, e.g. 640x480"))?;
    let content = Content::open(&scene, None, &NoProgress)?;
    let mut engine = Engine::open(
        content,
        &RenderOptions {
            size,
            ..RenderOptions::default()
        },
    )?;
    for w in engine.warnings() {
        eprintln!("warning: {w}");
    }
    let frame = engine.render()?;
    engine.save_png(&out)?;
    println!(
        "wrote {} ({}x{}) with {} on {} in {:.1} ms",
        out.display(),
        size.0,
        size.1,
        engine.choice().pipeline,
        engine.adapter(),
        frame.frame_wall_ms
    );
    Ok(())
}
