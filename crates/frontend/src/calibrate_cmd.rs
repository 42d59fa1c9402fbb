//! `ssbvb calibrate`: the bundled default scene drawn with each SSBVB form that fits the
//! adapter the default pipeline's rule picks, timed, and stored fastest first
//! (`ssbvb_engine::calibration`), so that `render`, `view`, `adapter` and the bench's `ssbvb` use
//! the form measured fastest on this adapter, driver and limits.

use anyhow::Result;
use clap::Args;
use ssbvb_passes::Profiling;

use crate::pipeline_cmd::parse_size;
use ssbvb_engine::calibration::{AdapterKey, Entry, FormTime, forms, path, store};
use ssbvb_engine::session::SessionSource;

/// Arguments of `ssbvb calibrate`.
#[derive(Args, Debug)]
pub struct CalibrateArgs {
    /// Image size of the measured frames.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Timed frames per form (after two warm-up frames); their median is kept.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub frames: u32,
    /// The device's limits (`webgpu`: WebGPU's defaults), part of the entry's key.
    #[arg(long, value_enum, default_value = "adapter")]
    pub limits: crate::adapter_cmd::LimitsArg,
}

/// Runs `ssbvb calibrate`: the bundled default scene drawn with each form that fits the
/// adapter the rule would pick, the median of `frames` frames each, stored fastest first.
pub fn run(args: &CalibrateArgs) -> Result<()> {
    let scene_path = ssbvb_engine::assets::assets_dir().join(ssbvb_engine::assets::DEFAULT_SCENE);
    let progress = crate::progress::BarProgress::new(false);
    let loaded = ssbvb_engine::scene_file::load(&scene_path, &progress)?;
    let (adapter, fitting) = crate::pipeline_choice::adapter_and_fitting_forms(&forms())?;
    let key = AdapterKey::of(&adapter, crate::adapter_cmd::limits().name());
    let mut times_of = Vec::new();
    for file in fitting {
        let path = ssbvb_engine::assets::assets_dir().join(file);
        let mut source = SessionSource {
            scene: loaded.scene.clone(),
            pipeline: crate::adapter_cmd::resolve(&path)?,
            budget: None,
            page_sources: Vec::new(),
            animated: Vec::new(),
            time: 0.0,
            size: args.size,
            time_submissions: false,
            instance_lists: true,
            counting: false,
            limits: crate::adapter_cmd::limits(),
            host: None,
        };
        let mut s = source.open_refusing(&mut Vec::new(), false)?.session;
        let gpu_clock = s.ctx.report().timestamps && !s.ctx.report().is_software;
        let mut times = Vec::new();
        for i in 0..args.frames + 2 {
            let stats =
                s.renderer
                    .render(&s.ctx, &mut s.scene, &loaded.camera, Profiling::Timestamps)?;
            let gpu: Option<f64> = stats.passes.iter().map(|p| p.gpu_ms).sum();
            if i >= 2 {
                times.push(gpu.filter(|_| gpu_clock).unwrap_or(stats.frame_wall_ms));
            }
        }
        times.sort_by(f64::total_cmp);
        times_of.push(FormTime {
            pipeline: file.to_string(),
            frame_ms: times[times.len() / 2],
            clock: if gpu_clock { "gpu" } else { "wall" }.into(),
        });
    }
    // Fastest first; a tie keeps the rule's order (a stable sort).
    times_of.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
    let entry = Entry {
        adapter: key,
        scene: ssbvb_engine::assets::DEFAULT_SCENE.into(),
        size: [args.size.0, args.size.1],
        forms: times_of,
    };
    let out = path();
    println!(
        "calibrated {} [{}, {}, {}] under {} limits: {}",
        entry.adapter.name,
        entry.adapter.backend,
        entry.adapter.device_type,
        entry.adapter.driver,
        entry.adapter.limits,
        entry.summary()
    );
    store(&out, entry)?;
    println!("wrote {}", out.display());
    Ok(())
}
