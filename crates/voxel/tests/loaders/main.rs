//! Integration tests of the model loaders: the real test models (`assets/models`), hand-written fixtures
//! of every format, malformed inputs (with file and line/offset in the message), and
//! deterministic plus property-based mutation of inputs (no panic, ever).
//!
//! One module per concern: the real models, then each format's fixtures and errors, raw
//! grids, format dispatch and the property-based tests; the shared helpers are here.

mod dispatch;
mod fuzz;
mod gltf;
mod obj;
mod ply;
mod raw;
mod real_models;
mod vox;

use std::path::{Path, PathBuf};

use glam::Vec3;
use ssbvb_voxel::load::{Format, LoadError, LoadOptions, load_from_bytes};
use ssbvb_voxel::model::{Mesh, Model, VoxelModel};

// ---------------------------------------------------------------------------------------
// Helpers

/// The repository's test models (`assets/models`); a missing folder is a failure, never a
/// silent skip.
fn models_dir() -> PathBuf {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/models"));
    assert!(
        dir.is_dir(),
        "the test models are missing: expected them in {}",
        dir.display()
    );
    dir
}

fn model(name: &str) -> PathBuf {
    let p = models_dir().join(name);
    assert!(p.is_file(), "test model {} is missing", p.display());
    p
}

fn mesh_of(model: Model) -> Mesh {
    match model {
        Model::Mesh(m) => m,
        Model::Voxels(_) => panic!("expected a mesh"),
    }
}

fn voxels_of(model: Model) -> VoxelModel {
    match model {
        Model::Voxels(v) => v,
        Model::Mesh(_) => panic!("expected voxels"),
    }
}

/// Parses bytes as `format` with no file access; the name only appears in messages.
fn parse(bytes: &[u8], format: Format, name: &str) -> Result<Model, LoadError> {
    load_from_bytes(
        bytes,
        format,
        Path::new(name),
        None,
        &LoadOptions::default(),
    )
    .map(|l| l.model)
}

fn parse_err(bytes: &[u8], format: Format, name: &str) -> LoadError {
    match parse(bytes, format, name) {
        Ok(_) => panic!("{name}: expected an error"),
        Err(e) => e,
    }
}

fn bounds(points: impl IntoIterator<Item = Vec3>) -> (Vec3, Vec3) {
    points.into_iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

fn assert_mesh_invariants(m: &Mesh) {
    let n = m.positions.len();
    assert!(m.normals.is_empty() || m.normals.len() == n);
    assert!(m.uvs.is_empty() || m.uvs.len() == n);
    assert!(m.colors.is_empty() || m.colors.len() == n);
    assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < n));
    assert!(m.positions.iter().all(|p| p.is_finite()));
    if !m.triangle_materials.is_empty() {
        assert_eq!(m.triangle_materials.len(), m.triangles.len());
        assert!(
            m.triangle_materials
                .iter()
                .all(|&i| (i as usize) < m.materials.len())
        );
    }
}

fn approx(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-4
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let v = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                out.push(A[(v >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A tiny deterministic PRNG for the mutation loops (reproducible failures).
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// What every successfully loaded model must be, checked here independently of the
/// loaders' own checks: a mesh with triangles whose indices are in range, finite
/// positions, attribute arrays empty or one per vertex, material indices in range; voxels
/// with one colour each (or none).
fn assert_usable(model: &Model, name: &str, what: &str) {
    match model {
        Model::Mesh(m) => {
            let n = m.positions.len();
            assert!(
                !m.triangles.is_empty(),
                "{name} ({what}): Ok without triangles"
            );
            assert!(
                m.triangles.iter().flatten().all(|&i| (i as usize) < n),
                "{name} ({what}): triangle index out of range"
            );
            assert!(
                m.positions.iter().all(|p| p.is_finite()),
                "{name} ({what}): non-finite position"
            );
            for (len, attr) in [
                (m.normals.len(), "normals"),
                (m.uvs.len(), "uvs"),
                (m.colors.len(), "colors"),
            ] {
                assert!(
                    len == 0 || len == n,
                    "{name} ({what}): {len} {attr} for {n} vertices"
                );
            }
            assert!(
                m.triangle_materials.is_empty()
                    || (m.triangle_materials.len() == m.triangles.len()
                        && m.triangle_materials
                            .iter()
                            .all(|&t| (t as usize) < m.materials.len().max(1))),
                "{name} ({what}): material index out of range"
            );
        }
        Model::Voxels(v) => {
            assert!(
                v.colors.is_empty() || v.colors.len() == v.voxels.len(),
                "{name} ({what}): {} colours for {} voxels",
                v.colors.len(),
                v.voxels.len()
            );
        }
    }
}

/// Truncations at many offsets and random byte flips of `bytes`: every result must be a
/// usable model ([`assert_usable`]) or an `Err` whose message names the file (a panic fails
/// the test).
fn mutate_and_parse(bytes: &[u8], format: Format, name: &str, truncations: usize, flips: usize) {
    let step = (bytes.len() / truncations.max(1)).max(1);
    let mut cut = 0;
    while cut < bytes.len() {
        match parse(&bytes[..cut], format, name) {
            Ok(m) => assert_usable(&m, name, &format!("cut at {cut}")),
            Err(e) => assert!(
                e.to_string().starts_with(name),
                "message must name the file: {e}"
            ),
        }
        cut += step;
    }
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15 ^ bytes.len() as u64);
    let mut buf = bytes.to_vec();
    for _ in 0..flips {
        buf.copy_from_slice(bytes);
        for _ in 0..1 + rng.below(4) {
            let at = rng.below(buf.len());
            buf[at] = match rng.below(4) {
                0 => 0,
                1 => 0xFF,
                2 => buf[at] ^ (1 << rng.below(8)),
                _ => rng.next() as u8,
            };
        }
        match parse(&buf, format, name) {
            Ok(m) => assert_usable(&m, name, "flipped bytes"),
            Err(e) => assert!(
                e.to_string().starts_with(name),
                "message must name the file: {e}"
            ),
        }
    }
}
