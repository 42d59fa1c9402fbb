//! Voxels from arrays against the same voxels from their model file: the first frame of a
//! sparse voxel list read from an `.npy` file (as `ssbvb export --format npy --sparse`
//! writes it), preparation included, and the later frames of both.
//!
//! `cargo run --release -p ssbvb-engine --example arrays_timing -- SPARSE.npy MODEL LEVEL WxH`
//!
//! The arrays are placed where the model's level-`LEVEL` grid lies (origin (-1, -1, -1),
//! voxels of 2 / 2^LEVEL), so both are seen by the model's camera.

use std::path::{Path, PathBuf};
use std::time::Instant;

use ssbvb_engine::arrays::{Array, ArrayData, Placement, SparseColors, VoxelArrays};
use ssbvb_engine::{Content, Engine, RenderOptions};
use ssbvb_voxel::progress::NoProgress;

/// Bytes of one record of the sparse `.npy`: x, y, z (`u16`), r, g, b, a (`u8`), the
/// normal (3 × `f32`).
const RECORD: usize = 22;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // SAFETY: first thing in `main`, before any other thread exists.
    unsafe { ssbvb_engine::platform::quiet_window_system_probe() };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [npy, model, level, size] = args.as_slice() else {
        return Err("usage: arrays_timing SPARSE.npy MODEL LEVEL WxH".into());
    };
    let level: u32 = level.parse()?;
    let size = ssbvb_engine::values::parse_size(size)?;
    let (coords, colors) = read_sparse(Path::new(npy))?;
    let n = coords.len() / 3;
    let options = RenderOptions {
        size,
        ..RenderOptions::default()
    };
    let camera = Content::default_camera();

    let t0 = Instant::now();
    let arrays = VoxelArrays::Sparse {
        coords: Array::new(vec![n, 3], ArrayData::I32(&coords)),
        colors: SparseColors::Each(Array::new(vec![n, 4], ArrayData::U8(&colors))),
    };
    let placement = Placement {
        origin: [-1.0; 3],
        voxel_size: 2.0 / f64::from(1u32 << level),
    };
    let content = Content::from_arrays(&arrays, placement, &NoProgress)?;
    let prepared_ms = ms(t0);
    let mut from_arrays = Engine::open(content, &options)?;
    let opened_ms = ms(t0);
    from_arrays.set_camera(camera);
    from_arrays.render()?;
    let image = from_arrays.read_rgba8()?;
    let first_ms = ms(t0);
    let arrays_ms = later_frames(&mut from_arrays)?;

    let content = Content::open(&PathBuf::from(model), Some(level), &NoProgress)?;
    let mut from_model = Engine::open(content, &options)?;
    from_model.set_camera(camera);
    let model_ms = later_frames(&mut from_model)?;
    let covered = |rgba: &[u8]| rgba.chunks(4).filter(|p| p[3] > 0).count();
    let model_image = from_model.read_rgba8()?;
    println!(
        "{{\"voxels\": {n}, \"size\": [{}, {}], \"adapter\": {:?}, \"pipeline\": {:?}, \
         \"arrays_prepared_ms\": {prepared_ms:.1}, \"arrays_opened_ms\": {opened_ms:.1}, \
         \"arrays_first_frame_ms\": {first_ms:.1}, \
         \"arrays_frame_ms\": {arrays_ms:.1}, \"model_frame_ms\": {model_ms:.1}, \
         \"arrays_covered_px\": {}, \"model_covered_px\": {}}}",
        size.0,
        size.1,
        from_arrays.adapter(),
        from_arrays.choice().pipeline,
        covered(&image),
        covered(&model_image)
    );
    Ok(())
}

fn ms(t0: Instant) -> f64 {
    t0.elapsed().as_secs_f64() * 1e3
}

/// The median wall time of five frames (ms).
fn later_frames(engine: &mut Engine) -> Result<f64, Box<dyn std::error::Error>> {
    let mut times = Vec::new();
    for _ in 0..5 {
        times.push(engine.render()?.frame_wall_ms);
    }
    times.sort_by(f64::total_cmp);
    Ok(times[times.len() / 2])
}

/// The coordinates (`i32`, 3 per voxel) and colours (RGBA bytes) of a sparse `.npy`.
fn read_sparse(path: &Path) -> Result<(Vec<i32>, Vec<u8>), Box<dyn std::error::Error>> {
    let bytes = std::fs::read(path)?;
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(format!("{}: not an .npy file", path.display()).into());
    }
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len])?;
    let count: usize = header
        .split("'shape': (")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .ok_or("no shape in the header")?
        .trim()
        .parse()?;
    let data = &bytes[10 + header_len..];
    if data.len() != count * RECORD {
        return Err(format!("{}: {count} records expected", path.display()).into());
    }
    let (mut coords, mut colors) = (Vec::with_capacity(count * 3), Vec::with_capacity(count * 4));
    for r in data.chunks_exact(RECORD) {
        for k in 0..3 {
            coords.push(i32::from(u16::from_le_bytes([r[2 * k], r[2 * k + 1]])));
        }
        colors.extend_from_slice(&r[6..10]);
    }
    Ok((coords, colors))
}
