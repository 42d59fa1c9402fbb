//! Integration tests of the model loaders: the real test models (`assets/models`), hand-written fixtures
//! of every format, malformed inputs (with file and line/offset in the message), and
//! deterministic plus property-based mutation of inputs (no panic, ever).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use proptest::prelude::*;
use ssbvb_voxel::load::{
    Format, LoadError, LoadOptions, load_from_bytes, load_mesh, load_model, load_model_with,
    load_vox_model, srgb_to_linear, write_raw,
};
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

/// Truncations at many offsets and random byte flips of `bytes`: every result must be an
/// `Ok` or an `Err` whose message names the file (a panic fails the test).
fn mutate_and_parse(bytes: &[u8], format: Format, name: &str, truncations: usize, flips: usize) {
    let step = (bytes.len() / truncations.max(1)).max(1);
    let mut cut = 0;
    while cut < bytes.len() {
        if let Err(e) = parse(&bytes[..cut], format, name) {
            assert!(
                e.to_string().starts_with(name),
                "message must name the file: {e}"
            );
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
        if let Err(e) = parse(&buf, format, name) {
            assert!(
                e.to_string().starts_with(name),
                "message must name the file: {e}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// The real test models

#[test]
fn bunny_obj_loads_with_exact_counts() {
    let t = Instant::now();
    let m = load_mesh(&model("bunny.obj")).unwrap();
    eprintln!("bunny: {:?}", t.elapsed());
    assert_eq!(m.triangles.len(), 69_451);
    // The file has 35,947 vertices, 1,113 of which no face uses; de-indexing keeps the
    // 34,834 referenced ones (unreferenced vertices would only distort the bounds).
    assert_eq!(m.positions.len(), 34_834);
    assert_mesh_invariants(&m);
    let (lo, hi) = bounds(m.positions.iter().copied());
    let extent = hi - lo;
    assert!(
        extent.min_element() > 0.01 && extent.max_element() < 10.0,
        "bunny bounds {lo} {hi}"
    );
    assert!(m.materials.is_empty() && m.triangle_materials.is_empty());
}

#[test]
fn teapot_and_cow_obj_load() {
    for (name, faces) in [("teapot.obj", 6_320), ("cow.obj", 5_804)] {
        let m = mesh_of(load_model(&model(name)).unwrap());
        assert_mesh_invariants(&m);
        assert!(
            m.triangles.len() >= faces,
            "{name}: {} triangles for {faces} faces",
            m.triangles.len()
        );
    }
}

/// Differential test: our OBJ reader against `tobj` on the test models (same triangles,
/// same corner positions).
#[test]
fn obj_reader_agrees_with_tobj() {
    for name in ["bunny.obj", "teapot.obj", "cow.obj"] {
        let path = model(name);
        let ours = load_mesh(&path).unwrap();
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj(&path, &options).unwrap();
        let mut theirs: Vec<[f32; 9]> = Vec::new();
        for model in &models {
            let mesh = &model.mesh;
            for tri in mesh.indices.chunks_exact(3) {
                let mut corners = [0f32; 9];
                for (k, &i) in tri.iter().enumerate() {
                    corners[k * 3..k * 3 + 3]
                        .copy_from_slice(&mesh.positions[i as usize * 3..i as usize * 3 + 3]);
                }
                theirs.push(corners);
            }
        }
        assert_eq!(ours.triangles.len(), theirs.len(), "{name}: triangle count");
        for (t, expected) in ours.triangles.iter().zip(&theirs) {
            for k in 0..3 {
                let p = ours.positions[t[k] as usize];
                assert_eq!(
                    [p.x, p.y, p.z],
                    expected[k * 3..k * 3 + 3],
                    "{name}: corner differs"
                );
            }
        }
    }
}

#[test]
fn igea_ply_tristrips_load() {
    let t = Instant::now();
    let m = load_mesh(&model("igea.ply")).unwrap();
    eprintln!("igea: {:?}, {} triangles", t.elapsed(), m.triangles.len());
    assert_eq!(m.positions.len(), 134_345);
    assert_mesh_invariants(&m);
    // igea is a closed genus-0 surface: Euler's formula gives T = 2V − 4 exactly, which
    // only holds if strips, restarts and stitching triangles are all decoded right.
    assert_eq!(m.triangles.len(), 2 * 134_345 - 4);
    assert!(
        m.triangles
            .iter()
            .all(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
    );
    // Strips alternate winding: on a consistently wound closed surface every directed edge
    // appears exactly once, and its reverse once.
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &m.triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    assert!(
        directed.values().all(|&c| c == 1),
        "igea: a directed edge repeats: inconsistent winding"
    );
    assert!(
        directed
            .keys()
            .all(|&(a, b)| directed.contains_key(&(b, a))),
        "igea: not closed"
    );
}

/// Differential test against `dot_vox`: same voxels (converted) and colours.
#[test]
fn vox_reader_agrees_with_dot_vox() {
    for name in ["chr_knight.vox", "T-Rex.vox", "monu1.vox"] {
        let path = model(name);
        let data = dot_vox::load(path.to_str().unwrap()).unwrap();
        for (k, model) in data.models.iter().enumerate() {
            let ours = load_vox_model(&path, k).unwrap();
            assert_eq!(
                ours.voxels.len(),
                model.voxels.len(),
                "{name} model {k}: voxel count"
            );
            for (v, (p, c)) in model
                .voxels
                .iter()
                .zip(ours.voxels.iter().zip(&ours.colors))
            {
                // Z-up → Y-up: (x, y, z) ↦ (x, z, −y − 1) for the cube's minimum corner.
                assert_eq!(
                    *p,
                    [v.x as i32, v.z as i32, -(v.y as i32) - 1],
                    "{name}: position"
                );
                let col = data.palette[v.i as usize];
                let expected = [
                    srgb_to_linear(col.r as f32 / 255.0),
                    srgb_to_linear(col.g as f32 / 255.0),
                ];
                assert!(
                    approx(c[0], expected[0]) && approx(c[1], expected[1]),
                    "{name}: colour"
                );
                assert!(approx(c[3], col.a as f32 / 255.0));
            }
        }
        assert!(load_vox_model(&path, data.models.len()).is_err());
    }
}

#[test]
fn vox_shared_models_load_whole() {
    // T-Rex: 8 animation frames, no scene graph: all frames at their own origin.
    let trex = voxels_of(load_model(&model("T-Rex.vox")).unwrap());
    let frame0 = load_vox_model(&model("T-Rex.vox"), 0).unwrap();
    assert!(trex.voxels.len() >= frame0.voxels.len());
    let (lo, hi) = voxel_bounds(&trex);
    assert!(
        lo.iter().zip(hi).all(|(l, h)| h - l < 26 && *l >= -26),
        "T-Rex bounds {lo:?} {hi:?}"
    );

    for name in ["chr_knight.vox", "monu1.vox"] {
        let v = voxels_of(load_model(&model(name)).unwrap());
        assert_eq!(v.voxels.len(), v.colors.len());
        let (lo, hi) = voxel_bounds(&v);
        assert!(
            lo.iter().zip(hi).all(|(l, h)| h - l < 256),
            "{name} bounds {lo:?} {hi:?}"
        );
        // Y-up: the Z extent of MagicaVoxel becomes the Y extent.
        let data = dot_vox::load(model(name).to_str().unwrap()).unwrap();
        let size = data.models[0].size;
        assert!(hi[1] - lo[1] < size.z as i32 && hi[2] - lo[2] < size.y as i32);
        let mut unique = v.voxels.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), v.voxels.len(), "{name}: duplicate voxels");
    }
}

fn voxel_bounds(v: &VoxelModel) -> ([i32; 3], [i32; 3]) {
    let mut lo = [i32::MAX; 3];
    let mut hi = [i32::MIN; 3];
    for p in &v.voxels {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

#[test]
fn every_shared_model_loads_through_load_model() {
    for entry in std::fs::read_dir(models_dir()).unwrap() {
        let path = entry.unwrap().path();
        if Format::from_path(&path).is_some() {
            let loaded = load_model_with(&path, &LoadOptions::default()).unwrap();
            assert!(
                loaded.warnings.is_empty(),
                "{}: {:?}",
                path.display(),
                loaded.warnings
            );
        }
    }
}

#[test]
fn truncated_and_flipped_real_models_never_panic() {
    for (name, format, truncations, flips) in [
        ("chr_knight.vox", Format::Vox, 400, 400),
        ("T-Rex.vox", Format::Vox, 150, 150),
        ("cow.obj", Format::Obj, 60, 60),
        ("igea.ply", Format::Ply, 12, 12),
    ] {
        let bytes = std::fs::read(model(name)).unwrap();
        mutate_and_parse(&bytes, format, name, truncations, flips);
    }
    // The PLY header and the first vertices, cut and flipped densely.
    let igea = std::fs::read(model("igea.ply")).unwrap();
    let mut head = igea[..4096].to_vec();
    // Keep it consistent: declare as many vertices as the 4096 bytes can hold, no strips.
    let text = String::from_utf8_lossy(&head[..200]).into_owned();
    let end = text.find("end_header\n").unwrap() + "end_header\n".len();
    let body = &igea[end..4096];
    let n = body.len() / 12;
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    );
    head = header.into_bytes();
    head.extend_from_slice(&body[..n * 12]);
    head.extend_from_slice(&[3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
    assert_eq!(
        mesh_of(parse(&head, Format::Ply, "head.ply").unwrap())
            .triangles
            .len(),
        1
    );
    mutate_and_parse(&head, Format::Ply, "head.ply", 300, 600);
}

// ---------------------------------------------------------------------------------------
// OBJ fixtures and errors

#[test]
fn obj_with_negative_indices_quads_and_mtl() {
    let dir = tempfile::tempdir().unwrap();
    // A 2×1 sRGB texture: one mid-grey texel and one white texel.
    let img =
        image::RgbaImage::from_raw(2, 1, vec![128, 128, 128, 255, 255, 255, 255, 128]).unwrap();
    img.save(dir.path().join("tex.png")).unwrap();
    std::fs::write(
        dir.path().join("m.mtl"),
        "# materials\nnewmtl red\nKd 1 0 0\nd 0.5\nnewmtl textured\nmap_Kd -s 1 1 1 tex.png\nnewmtl grey\nKd 0.25\n",
    )
    .unwrap();
    let obj = "mtllib m.mtl\n\
               v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
               vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               vn 0 0 1\n\
               usemtl red\n\
               f -4/-4/-1 -3/-3/-1 -2/-2/-1 -1/-1/-1\n\
               usemtl textured\n\
               f 1/1/1 2/2/1 3/3/1\n\
               usemtl missing\n\
               f 1/1/1 3/3/1 4/4/1\n";
    let path = dir.path().join("quad.obj");
    std::fs::write(&path, obj).unwrap();
    let loaded = load_model_with(&path, &LoadOptions::default()).unwrap();
    let m = mesh_of(loaded.model);
    assert_mesh_invariants(&m);
    assert_eq!(m.triangles.len(), 4);
    assert_eq!(
        m.positions.len(),
        4,
        "same (v, vt, vn) corners share a vertex"
    );
    assert_eq!(m.normals.len(), 4);
    assert_eq!(m.uvs.len(), 4);
    assert_eq!(m.triangle_materials, vec![0, 0, 1, 2]);
    assert_eq!(m.materials[0].base_color, [1.0, 0.0, 0.0, 0.5]);
    let tex = m.materials[1]
        .base_color_texture
        .as_ref()
        .expect("texture loaded");
    assert_eq!((tex.width, tex.height), (2, 1));
    // sRGB 128 → linear 0.2158 → 55; alpha untouched.
    assert_eq!(tex.texels[0], [55, 55, 55, 255]);
    assert_eq!(tex.texels[1], [255, 255, 255, 128]);
    assert_eq!(m.materials[1].base_color, [1.0; 4]);
    assert_eq!(m.materials[2].base_color, [0.8, 0.8, 0.8, 1.0]);
    assert!(
        loaded.warnings.iter().any(|w| w.contains("\"missing\"")),
        "{:?}",
        loaded.warnings
    );
}

#[test]
fn obj_missing_mtl_and_texture_are_warnings() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("a.mtl"),
        "newmtl a\nKd 0.1 0.2 0.3\nmap_Kd nothere.png\n",
    )
    .unwrap();
    let path = dir.path().join("a.obj");
    std::fs::write(
        &path,
        "mtllib a.mtl nope.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    )
    .unwrap();
    let loaded = load_model_with(&path, &LoadOptions::default()).unwrap();
    assert_eq!(loaded.warnings.len(), 2, "{:?}", loaded.warnings);
    assert!(loaded.warnings.iter().any(|w| w.contains("nope.mtl")));
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("nothere.png") && w.contains("a.mtl:3"))
    );
    let m = mesh_of(loaded.model);
    assert_eq!(m.materials[0].base_color, [0.1, 0.2, 0.3, 1.0]);
}

#[test]
fn obj_vertex_colours_are_decoded_to_linear() {
    let obj = "v 0 0 0 1 0.5 0\nv 1 0 0 0 0 0\nv 0 1 0 1 1 1\nf 1 2 3\n";
    let m = mesh_of(parse(obj.as_bytes(), Format::Obj, "c.obj").unwrap());
    assert_eq!(m.colors.len(), 3);
    assert!(approx(m.colors[0][1], srgb_to_linear(0.5)));
    assert_eq!(m.colors[0][3], 1.0);
}

#[test]
fn obj_errors_name_file_and_line() {
    let cases: &[(&str, usize, &str)] = &[
        (
            "v 0 0 0\nv 1 0 0\nv 0 x 0\nf 1 2 3\n",
            3,
            "not a finite number",
        ),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n", 5, "out of range"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", 4, "out of range"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 4, "index 0"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n",
            4,
            "texture coordinate index 1 is out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//2 2//2 3//2\n",
            4,
            "normal index",
        ),
        ("v 0 0\n", 1, "3 coordinates"),
        ("v 1e39 0 0\n", 1, "finite"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/2/3/4 2 3\n", 4, "malformed"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n",
            4,
            "not an integer",
        ),
        (
            "# c\nv 0 0 0 \\\n 1\nv 1 0 0\nv 0 1 0\nf 1 2 3 x\n",
            6,
            "not an integer",
        ),
    ];
    for (text, line, needle) in cases {
        let e = parse_err(text.as_bytes(), Format::Obj, "bad.obj");
        let msg = e.to_string();
        assert_eq!(e.line(), Some(*line), "{msg}");
        assert!(msg.starts_with(&format!("bad.obj:{line}: ")), "{msg}");
        assert!(msg.contains(needle), "{msg} should contain {needle:?}");
    }
    // An MTL error names the MTL file and its line.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("b.mtl"), "newmtl a\nKd 1 2\n").unwrap();
    let path = dir.path().join("b.obj");
    std::fs::write(
        &path,
        "mtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    )
    .unwrap();
    let e = load_model(&path).unwrap_err();
    assert!(e.to_string().contains("b.mtl:2: "), "{e}");
    // No geometry.
    assert!(matches!(
        parse_err(b"# nothing\nv 0 0 0\n", Format::Obj, "e.obj"),
        LoadError::Empty { .. }
    ));
}

// ---------------------------------------------------------------------------------------
// PLY fixtures and errors

const ASCII_PLY: &str = "ply\n\
format ascii 1.0\n\
comment a quad and a triangle\n\
element vertex 5\n\
property float x\nproperty float y\nproperty float z\n\
property float nx\nproperty float ny\nproperty float nz\n\
property uchar red\nproperty uchar green\nproperty uchar blue\n\
property float u\nproperty float v\n\
element face 2\n\
property list uchar int vertex_indices\n\
end_header\n\
0 0 0 0 0 1 255 0 0 0 0\n\
1 0 0 0 0 1 0 255 0 1 0\n\
1 1 0 0 0 1 0 0 255 1 1\n\
0 1 0 0 0 1 128 128 128 0 1\n\
2 2 2 0 0 1 0 0 0 0.5 0.5\n\
4 0 1 2 3\n\
3 1 2 4\n";

#[test]
fn ascii_ply_with_attributes() {
    let m = mesh_of(parse(ASCII_PLY.as_bytes(), Format::Ply, "a.ply").unwrap());
    assert_mesh_invariants(&m);
    assert_eq!(m.positions.len(), 5);
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 2, 4]]);
    assert_eq!(m.normals[0], Vec3::Z);
    assert_eq!(m.colors[0], [1.0, 0.0, 0.0, 1.0]);
    assert!(approx(m.colors[3][0], srgb_to_linear(128.0 / 255.0)));
    assert_eq!(m.uvs[4], glam::Vec2::new(0.5, 0.5));
}

fn binary_ply(big_endian: bool) -> Vec<u8> {
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n\
         element material 2\nproperty list uchar float stuff\n\
         element face 1\nproperty uchar flags\nproperty list uchar uint vertex_indices\nend_header\n"
    )
    .into_bytes();
    let f64b = |v: f64| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let u32b = |v: u32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let f32b = |v: f32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    for (i, p) in [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.5],
    ]
    .iter()
    .enumerate()
    {
        for c in p {
            out.extend_from_slice(&f64b(*c));
        }
        out.extend_from_slice(&[255, 0, (i * 60) as u8, 128]);
    }
    out.push(1);
    out.extend_from_slice(&f32b(1.5));
    out.push(0);
    out.push(7); // flags
    out.push(4);
    for i in [0u32, 1, 2, 3] {
        out.extend_from_slice(&u32b(i));
    }
    out
}

#[test]
fn binary_ply_both_endiannesses() {
    for be in [false, true] {
        let bytes = binary_ply(be);
        let m = mesh_of(parse(&bytes, Format::Ply, "b.ply").unwrap());
        assert_mesh_invariants(&m);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.positions[3], Vec3::new(0.0, 1.0, 0.5));
        assert_eq!(m.colors[0][0], 1.0);
        assert!(approx(m.colors[0][3], 128.0 / 255.0), "alpha is linear");
        // Truncations anywhere in the body give an offset-located error.
        let header_len = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        for cut in header_len..bytes.len() {
            let e = parse_err(&bytes[..cut], Format::Ply, "b.ply");
            assert!(e.offset().is_some(), "{e}");
            assert!(e.to_string().starts_with("b.ply: byte "), "{e}");
        }
        mutate_and_parse(&bytes, Format::Ply, "b.ply", bytes.len(), 500);
    }
}

#[test]
fn binary_ply_tristrips_alternate_winding() {
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n".to_vec();
    for p in [
        [0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [2.0, 0.0, 0.0],
    ] {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    let strip: [i32; 10] = [0, 1, 2, 3, -1, 1, 4, 3, 3, 3];
    bytes.extend_from_slice(&(strip.len() as i32).to_le_bytes());
    for i in strip {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    let m = mesh_of(parse(&bytes, Format::Ply, "s.ply").unwrap());
    // (0 1 2), (2 1 3) [odd: swapped], restart, (1 4 3); (4 3 3), (3 3 3) are stitching.
    assert_eq!(m.triangles, vec![[0, 1, 2], [2, 1, 3], [1, 4, 3]]);
    // All three face +z (consistent winding).
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert!((b - a).cross(c - a).z > 0.0, "{t:?}");
    }
    mutate_and_parse(&bytes, Format::Ply, "s.ply", bytes.len(), 500);
}

#[test]
fn ply_errors_are_located_and_huge_counts_fail_fast() {
    // ASCII: bad value on line 21 (the body starts at line 19 in ASCII_PLY).
    let bad = ASCII_PLY.replace("1 1 0 0 0 1 0 0 255 1 1", "1 1 0 0 0 1 0 0 256 1 1");
    let e = parse_err(bad.as_bytes(), Format::Ply, "a.ply");
    assert_eq!(e.line(), Some(21), "{e}");
    let bad = ASCII_PLY.replace("3 1 2 4\n", "3 1 2 5\n");
    let e = parse_err(bad.as_bytes(), Format::Ply, "a.ply");
    assert!(
        e.line() == Some(25) && e.to_string().contains("out of range"),
        "{e}"
    );
    let bad = ASCII_PLY.replace("property float u\n", "property flaot u\n");
    assert_eq!(
        parse_err(bad.as_bytes(), Format::Ply, "a.ply").line(),
        Some(14)
    );
    let e = parse_err(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
        Format::Ply,
        "t.ply",
    );
    assert!(e.to_string().contains("end_header"), "{e}");

    // Absurd declared counts: refused from the header, before any allocation.
    let t = Instant::now();
    let huge = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    assert!(matches!(
        parse_err(huge, Format::Ply, "h.ply"),
        LoadError::TooLarge { .. }
    ));
    let big = b"ply\nformat binary_little_endian 1.0\nelement vertex 200000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0";
    let e = parse_err(big, Format::Ply, "h.ply");
    assert!(e.to_string().contains("only 4 bytes follow"), "{e}");
    let mut list = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n".to_vec();
    list.extend_from_slice(&[0u8; 36]);
    list.extend_from_slice(&u32::MAX.to_le_bytes());
    let e = parse_err(&list, Format::Ply, "h.ply");
    assert!(e.to_string().contains("runs past the end"), "{e}");
    assert!(t.elapsed().as_millis() < 500, "huge counts must fail fast");
}

// ---------------------------------------------------------------------------------------
// glTF / GLB fixtures and errors

/// One triangle (+ a fourth vertex for strips), u16 indices, normals; returns the buffer.
fn triangle_buffer() -> Vec<u8> {
    let mut b = Vec::new();
    for p in [
        [0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ] {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for _ in 0..4 {
        for c in [0f32, 0.0, 1.0] {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    // indices at 96: 0 1 2 (+ pad)
    for i in [0u16, 1, 2, 0] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    // sparse: index 1 (u8) at 104, value (5, 5, 5) at 108
    b.extend_from_slice(&[1, 0, 0, 0]);
    for c in [5f32, 5.0, 5.0] {
        b.extend_from_slice(&c.to_le_bytes());
    }
    b
}

fn triangle_gltf_json(buffer_uri: Option<&str>, extra_nodes: &str, mode: u32) -> String {
    let uri = buffer_uri
        .map(|u| format!(r#""uri": "{u}","#))
        .unwrap_or_default();
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [
    {{"translation": [10, 0, 0], "children": [1]}},
    {{"scale": [2, 2, 2], "mesh": 0}}{extra_nodes}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "indices": 2, "material": 0, "mode": {mode}}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [1, 0, 0, 1]}}}}],
  "buffers": [{{{uri} "byteLength": 120}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 8}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5123, "count": {count}, "type": "SCALAR"}}
  ]
}}"#,
        count = if mode == 4 { 3 } else { 4 }
    )
}

#[test]
fn gltf_with_node_transform_and_data_uri() {
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64(&triangle_buffer())
    );
    let json = triangle_gltf_json(Some(&uri), "", 4);
    let m = mesh_of(parse(json.as_bytes(), Format::Gltf, "t.gltf").unwrap());
    assert_mesh_invariants(&m);
    assert_eq!(m.triangles.len(), 1);
    let tri = m.triangles[0].map(|i| m.positions[i as usize]);
    assert_eq!(
        tri,
        [
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(12.0, 0.0, 0.0),
            Vec3::new(10.0, 2.0, 0.0)
        ]
    );
    assert!(m.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
    assert_eq!(
        m.materials[m.triangle_materials[0] as usize].base_color,
        [1.0, 0.0, 0.0, 1.0]
    );
    assert!(m.uvs.is_empty() && m.colors.is_empty());

    // The same file on disk with an external buffer beside it.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tri angle.bin"), triangle_buffer()).unwrap();
    let path = dir.path().join("t.GLTF");
    std::fs::write(&path, triangle_gltf_json(Some("tri%20angle.bin"), "", 4)).unwrap();
    let m2 = load_mesh(&path).unwrap();
    assert_eq!(m2.positions, m.positions);
    // In memory, an external buffer cannot be opened: an error, not a file access.
    let e = parse_err(
        triangle_gltf_json(Some("tri%20angle.bin"), "", 4).as_bytes(),
        Format::Gltf,
        "x.gltf",
    );
    assert!(e.to_string().contains("no base folder"), "{e}");
}

#[test]
fn gltf_strips_mirroring_and_sparse() {
    let buffer = triangle_buffer();
    let uri = format!("data:application/octet-stream;base64,{}", base64(&buffer));
    // TRIANGLE_STRIP over 0 1 2 0 → (0 1 2) and (2 1 0) swapped to (1 2 0)... the second
    // repeats index 0 twice? No: window (1 2 0) is odd → (2 1 0): a real triangle.
    let json = triangle_gltf_json(Some(&uri), "", 5);
    let m = mesh_of(parse(json.as_bytes(), Format::Gltf, "s.gltf").unwrap());
    assert_eq!(m.triangles, vec![[0, 1, 2], [2, 1, 0]]);

    // A mirroring node flips the winding back to front-facing.
    let json = triangle_gltf_json(Some(&uri), "", 4)
        .replace(r#""scale": [2, 2, 2]"#, r#""scale": [-1, 1, 1]"#);
    let m = mesh_of(parse(json.as_bytes(), Format::Gltf, "m.gltf").unwrap());
    let [a, b, c] = m.triangles[0].map(|i| m.positions[i as usize]);
    let n = (b - a).cross(c - a);
    assert!(n.z > 0.0, "winding must keep the normal's side: {n}");
    assert!((m.normals[0] - Vec3::Z).length() < 1e-6);

    // Sparse accessor: vertex 1 replaced by (5, 5, 5).
    let json = triangle_gltf_json(Some(&uri), "", 4)
        .replace(
            r#"{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}"#,
            r#"{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
            "sparse": {"count": 1, "indices": {"bufferView": 3, "componentType": 5121},
                       "values": {"bufferView": 4}}}"#,
        )
        .replace(
            r#"{"buffer": 0, "byteOffset": 96, "byteLength": 8}"#,
            r#"{"buffer": 0, "byteOffset": 96, "byteLength": 8},
           {"buffer": 0, "byteOffset": 104, "byteLength": 1},
           {"buffer": 0, "byteOffset": 108, "byteLength": 12}"#,
        );
    let m = mesh_of(parse(json.as_bytes(), Format::Gltf, "sp.gltf").unwrap());
    assert_eq!(m.positions[1], Vec3::new(20.0, 10.0, 10.0));
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

/// A GLB with an embedded PNG base colour texture and UVs.
fn textured_glb() -> Vec<u8> {
    let mut bin = triangle_buffer();
    bin.truncate(104);
    // uvs at 104: 4 × vec2
    for uv in [[0f32, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]] {
        for c in uv {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let mut png = Vec::new();
    image::RgbaImage::from_raw(1, 1, vec![128, 255, 0, 200])
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let png_at = bin.len();
    bin.extend_from_slice(&png);
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}},
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 3}}, "indices": 2, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}}}}}],
  "textures": [{{"source": 0}}],
  "images": [{{"bufferView": 4, "mimeType": "image/png"}}],
  "buffers": [{{"byteLength": {len}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 8}},
    {{"buffer": 0, "byteOffset": 104, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": {png_at}, "byteLength": {png_len}}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"}},
    {{"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC2"}}
  ]}}"#,
        len = bin.len(),
        png_len = png.len()
    );
    glb(&json, &bin)
}

#[test]
fn glb_with_embedded_texture() {
    let bytes = textured_glb();
    // No scene: root nodes are loaded.
    let m = mesh_of(parse(&bytes, Format::Glb, "t.glb").unwrap());
    assert_mesh_invariants(&m);
    assert_eq!(m.triangles.len(), 1);
    assert_eq!(m.uvs.len(), 4);
    assert!(m.normals.is_empty(), "no NORMAL attribute");
    let mat = &m.materials[0];
    assert_eq!(mat.base_color, [1.0; 4]);
    let tex = mat.base_color_texture.as_ref().unwrap();
    assert_eq!(tex.texels, vec![[55, 255, 0, 200]]);
    // By path, sniffed from content under an unknown extension.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.bin3d");
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(load_mesh(&path).unwrap().triangles.len(), 1);
    mutate_and_parse(&bytes, Format::Glb, "t.glb", 400, 1500);
}

#[test]
fn gltf_errors() {
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64(&triangle_buffer())
    );
    let good = triangle_gltf_json(Some(&uri), "", 4);
    // JSON syntax error: line reported.
    let e = parse_err(
        good.replacen("\"scene\": 0,", "\"scene\": 0,,", 1)
            .as_bytes(),
        Format::Gltf,
        "j.gltf",
    );
    assert_eq!(e.line(), Some(3), "{e}");
    // Index out of range.
    // Indices read from the normals' bytes: (0, 0, 0x3F80) with this offset.
    let bad = good.replace(
        r#"{"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"}"#,
        r#"{"bufferView": 1, "byteOffset": 6, "componentType": 5123, "count": 3, "type": "SCALAR"}"#,
    );
    let e = parse_err(bad.as_bytes(), Format::Gltf, "i.gltf");
    assert!(e.to_string().contains("out of range"), "{e}");
    // Accessor overrunning its view.
    let bad = good.replace(
        r#""count": 4, "type": "VEC3"}"#,
        r#""count": 400000000, "type": "VEC3"}"#,
    );
    let e = parse_err(bad.as_bytes(), Format::Gltf, "o.gltf");
    assert!(e.to_string().contains("overrun"), "{e}");
    // A huge zero-filled accessor (no bufferView) is refused, not allocated.
    let bad = good.replace(
        r#"{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}"#,
        r#"{"componentType": 5126, "count": 1000000000, "type": "VEC3",
            "sparse": {"count": 1, "indices": {"bufferView": 2, "componentType": 5121},
                       "values": {"bufferView": 0}}}"#,
    );
    let e = parse_err(bad.as_bytes(), Format::Gltf, "z.gltf");
    assert!(matches!(e, LoadError::TooLarge { .. }), "{e}");
    // Node cycle: ends, with a warning.
    let cyclic = good.replace(
        r#""scale": [2, 2, 2], "mesh": 0"#,
        r#""scale": [2, 2, 2], "mesh": 0, "children": [0]"#,
    );
    let loaded = load_from_bytes(
        cyclic.as_bytes(),
        Format::Gltf,
        Path::new("c.gltf"),
        None,
        &LoadOptions::default(),
    );
    if let Ok(l) = loaded {
        assert!(!l.warnings.is_empty());
    }
    // Out-of-range references anywhere are errors, not panics (gltf-json's own validation
    // pass panicked on the first of these: a fuzzing find).
    for (from, to) in [
        (r#""POSITION": 0"#, r#""POSITION": 5"#),
        (r#""indices": 2"#, r#""indices": 9"#),
        (r#""material": 0"#, r#""material": 3"#),
        (r#""mesh": 0"#, r#""mesh": 7"#),
        (r#""children": [1]"#, r#""children": [8]"#),
        (r#""nodes": [0]"#, r#""nodes": [4]"#),
        (r#""scene": 0"#, r#""scene": 2"#),
        (
            r#"{"buffer": 0, "byteOffset": 0"#,
            r#"{"buffer": 3, "byteOffset": 0"#,
        ),
        (r#"{"bufferView": 0, "#, r#"{"bufferView": 6, "#),
        (r#""componentType": 5126"#, r#""componentType": 1"#),
        (r#""type": "VEC3""#, r#""type": "MAT4""#),
        (r#""mode": 4"#, r#""mode": 99"#),
    ] {
        let bad = good.replacen(from, to, 1);
        assert_ne!(bad, good, "{from}");
        let e = parse_err(bad.as_bytes(), Format::Gltf, "r.gltf");
        assert!(e.to_string().starts_with("r.gltf"), "{e}");
    }
    // GLB container errors carry offsets.
    let glb_bytes = textured_glb();
    let mut bad = glb_bytes.clone();
    bad[8..12].copy_from_slice(&(glb_bytes.len() as u32 + 1).to_le_bytes());
    let e = parse_err(&bad, Format::Glb, "g.glb");
    assert_eq!(e.offset(), Some(8), "{e}");
    let mut bad = glb_bytes.clone();
    bad[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    assert_eq!(parse_err(&bad, Format::Glb, "g.glb").offset(), Some(12));
    assert!(
        parse_err(&glb_bytes[..11], Format::Glb, "g.glb")
            .to_string()
            .starts_with("g.glb: byte ")
    );
}

// ---------------------------------------------------------------------------------------
// .vox fixtures and errors

fn chunk(id: &[u8; 4], content: &[u8], children: &[u8]) -> Vec<u8> {
    let mut out = id.to_vec();
    out.extend_from_slice(&(content.len() as u32).to_le_bytes());
    out.extend_from_slice(&(children.len() as u32).to_le_bytes());
    out.extend_from_slice(content);
    out.extend_from_slice(children);
    out
}

fn vox_string(s: &str) -> Vec<u8> {
    let mut out = (s.len() as i32).to_le_bytes().to_vec();
    out.extend_from_slice(s.as_bytes());
    out
}

fn vox_dict(pairs: &[(&str, &str)]) -> Vec<u8> {
    let mut out = (pairs.len() as i32).to_le_bytes().to_vec();
    for (k, v) in pairs {
        out.extend(vox_string(k));
        out.extend(vox_string(v));
    }
    out
}

fn ints(v: &[i32]) -> Vec<u8> {
    v.iter().flat_map(|i| i.to_le_bytes()).collect()
}

fn vox_file(children: &[Vec<u8>]) -> Vec<u8> {
    let mut out = b"VOX ".to_vec();
    out.extend_from_slice(&150u32.to_le_bytes());
    out.extend(chunk(b"MAIN", &[], &children.concat()));
    out
}

fn ntrn(id: i32, child: i32, layer: i32, frame: &[(&str, &str)]) -> Vec<u8> {
    let mut c = ints(&[id]);
    c.extend(vox_dict(&[]));
    c.extend(ints(&[child, -1, layer, 1]));
    c.extend(vox_dict(frame));
    chunk(b"nTRN", &c, &[])
}

/// Two models, a group with three instances: translated, rotated, and on a hidden layer.
fn scene_vox() -> Vec<u8> {
    let size = |x: i32, y: i32, z: i32| chunk(b"SIZE", &ints(&[x, y, z]), &[]);
    let xyzi = |vs: &[[u8; 4]]| {
        let mut c = ints(&[vs.len() as i32]);
        c.extend(vs.iter().flatten());
        chunk(b"XYZI", &c, &[])
    };
    let mut palette = Vec::new();
    for i in 0..256u32 {
        palette.extend_from_slice(&[i as u8, 0, 0, 255]);
    }
    let mut group = ints(&[1]);
    group.extend(vox_dict(&[]));
    group.extend(ints(&[3, 2, 4, 6]));
    let shape = |id: i32, model: i32| {
        let mut c = ints(&[id]);
        c.extend(vox_dict(&[]));
        c.extend(ints(&[1, model]));
        c.extend(vox_dict(&[]));
        chunk(b"nSHP", &c, &[])
    };
    let mut layer = ints(&[1]);
    layer.extend(vox_dict(&[("_hidden", "1")]));
    layer.extend(ints(&[-1]));
    vox_file(&[
        size(2, 2, 2),
        xyzi(&[[0, 0, 0, 1], [1, 0, 0, 2]]),
        size(1, 1, 1),
        xyzi(&[[0, 0, 0, 3]]),
        chunk(b"RGBA", &palette, &[]),
        ntrn(0, 1, -1, &[]),
        chunk(b"nGRP", &group, &[]),
        ntrn(2, 3, 0, &[("_t", "10 0 0")]),
        shape(3, 0),
        // 90° about +z: row 0 = (0, −1, 0), row 1 = (1, 0, 0), row 2 = (0, 0, 1).
        ntrn(4, 5, 0, &[("_r", "17"), ("_t", "0 20 0")]),
        shape(5, 0),
        ntrn(6, 7, 1, &[("_t", "0 0 30")]),
        shape(7, 1),
        chunk(b"LAYR", &layer, &[]),
    ])
}

#[test]
fn vox_scene_graph_places_instances() {
    let bytes = scene_vox();
    let v = voxels_of(parse(&bytes, Format::Vox, "s.vox").unwrap());
    // Pivot (1, 1, 1). Instance 1: q = (−1,−1,−1), (0,−1,−1) + (10, 0, 0) → (9,−1,−1),
    // (10,−1,−1). Instance 2: rotated cubes' minimum corners (0,−1,−1), (0, 0,−1) + (0, 20,
    // 0) → (0, 19,−1), (0, 20,−1). Then Z-up → Y-up: (x, y, z) ↦ (x, z, −y − 1).
    let expected = [[9, -1, 0], [10, -1, 0], [0, -1, -20], [0, -1, -21]];
    assert_eq!(v.voxels, expected, "hidden layer must be skipped");
    // Palette entry k is colour index k + 1: index 1 → red byte 0, index 2 → red byte 1.
    assert_eq!(v.colors[0][0], 0.0);
    assert!(approx(v.colors[1][0], srgb_to_linear(1.0 / 255.0)));
    // dot_vox reads our fixture too (sanity of the writer).
    assert_eq!(dot_vox::load_bytes(&bytes).unwrap().models.len(), 2);
    mutate_and_parse(&bytes, Format::Vox, "s.vox", bytes.len(), 2000);
}

#[test]
fn vox_errors_and_limits() {
    let size = |x: i32, y: i32, z: i32| chunk(b"SIZE", &ints(&[x, y, z]), &[]);
    let e = parse_err(&vox_file(&[size(1 << 30, 1, 1)]), Format::Vox, "h.vox");
    assert!(matches!(e, LoadError::TooLarge { .. }), "{e}");
    let mut xyzi = ints(&[i32::MAX]);
    xyzi.extend([0, 0, 0, 1]);
    let e = parse_err(
        &vox_file(&[size(1, 1, 1), chunk(b"XYZI", &xyzi, &[])]),
        Format::Vox,
        "c.vox",
    );
    assert!(
        e.offset().is_some() && e.to_string().contains("does not fit"),
        "{e}"
    );
    let e = parse_err(
        b"VOX \x96\0\0\0MAIN\0\0\0\0\xff\xff\0\0",
        Format::Vox,
        "m.vox",
    );
    assert_eq!(e.offset(), Some(12), "{e}");
    assert!(matches!(
        parse_err(&vox_file(&[]), Format::Vox, "e.vox"),
        LoadError::Empty { .. }
    ));
    // Deeply nested chunks (a stack overflow for recursive readers) are just skipped.
    let levels = 100_000u32;
    let mut nested = Vec::with_capacity(12 * (levels as usize + 1));
    for k in 0..levels {
        nested.extend_from_slice(b"NEST");
        nested.extend_from_slice(&0u32.to_le_bytes());
        nested.extend_from_slice(&((levels - k) * 12).to_le_bytes());
    }
    nested.extend_from_slice(&chunk(b"XXXX", &[], &[]));
    let mut file = vec![
        size(1, 1, 1),
        chunk(b"XYZI", &[1, 0, 0, 0, 0, 0, 0, 1], &[]),
    ];
    file.push(nested);
    assert_eq!(
        voxels_of(parse(&vox_file(&file), Format::Vox, "n.vox").unwrap())
            .voxels
            .len(),
        1
    );
    // A scene-graph cycle terminates.
    let cyclic = vox_file(&[
        size(1, 1, 1),
        chunk(b"XYZI", &[1, 0, 0, 0, 0, 0, 0, 1], &[]),
        ntrn(0, 0, -1, &[]),
    ]);
    assert!(
        parse(&cyclic, Format::Vox, "y.vox").is_err(),
        "no instance: empty"
    );
    // Bad rotation byte: located.
    let bad = vox_file(&[
        size(1, 1, 1),
        chunk(b"XYZI", &[1, 0, 0, 0, 0, 0, 0, 1], &[]),
        ntrn(0, 1, -1, &[("_r", "3")]),
    ]);
    assert!(parse_err(&bad, Format::Vox, "r.vox").offset().is_some());
}

// ---------------------------------------------------------------------------------------
// Raw grids

#[test]
fn raw_round_trip_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.raw");
    let (nx, ny, nz) = (3u32, 2u32, 2u32);
    let mut cells = vec![0u8; 12];
    cells[1] = 255; // (1, 0, 0)
    cells[3 + 2] = 128; // (2, 1, 0)
    cells[6] = 1; // (0, 0, 1)
    write_raw(&path, nx, ny, nz, &cells).unwrap();
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 1, "no temporary file left behind: {names:?}");
    let v = voxels_of(load_model(&path).unwrap());
    assert_eq!(v.voxels, vec![[1, 0, 0], [2, 1, 0], [0, 0, 1]]);
    assert_eq!(v.colors[0], [1.0, 1.0, 1.0, 1.0]);
    assert!(approx(v.colors[1][0], srgb_to_linear(128.0 / 255.0)));
    // In memory gives the same.
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(
        voxels_of(parse(&bytes, Format::Raw, "g.raw").unwrap()).voxels,
        v.voxels
    );
    // Errors.
    assert!(write_raw(&path, 3, 2, 2, &cells[..11]).is_err());
    assert!(write_raw(&path, 5000, 1, 1, &[]).is_err());
    let e = parse_err(&bytes[..bytes.len() - 1], Format::Raw, "g.raw");
    assert!(
        e.offset().is_some() && e.to_string().contains("12 cells"),
        "{e}"
    );
    let e = parse_err(b"SSBVBRAW 4096 4096 4097\n", Format::Raw, "h.raw");
    assert!(matches!(e, LoadError::TooLarge { .. }), "{e}");
    let e = parse_err(b"SSBVBRAW 4096 4096 4096\n\x01", Format::Raw, "h.raw");
    assert!(e.to_string().contains("68719476736 cells"), "{e}");
    assert_eq!(
        parse_err(b"SSBVBRAW 1 x 1\n\x01", Format::Raw, "x.raw").line(),
        Some(1)
    );
    std::fs::write(&path, b"SSBVBRAW 2 2 2\n\0\0\0\0\0\0\0").unwrap();
    assert!(
        load_model(&path)
            .unwrap_err()
            .to_string()
            .contains("7 bytes follow")
    );
    mutate_and_parse(&bytes, Format::Raw, "g.raw", bytes.len(), 300);
}

// ---------------------------------------------------------------------------------------
// Dispatch

#[test]
fn format_dispatch_by_extension_and_content() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    for name in ["upper.OBJ", "sniffed.mesh", "noext"] {
        let p = dir.path().join(name);
        std::fs::write(&p, obj).unwrap();
        assert_eq!(load_mesh(&p).unwrap().triangles.len(), 1, "{name}");
    }
    let p = dir.path().join("x.ply3");
    std::fs::write(&p, ASCII_PLY).unwrap();
    assert_eq!(load_mesh(&p).unwrap().triangles.len(), 3);
    let p = dir.path().join("garbage.dat");
    std::fs::write(&p, [0u8, 1, 2, 3]).unwrap();
    assert!(matches!(
        load_model(&p),
        Err(LoadError::UnsupportedFormat { .. })
    ));
    let p = dir.path().join("v.vox");
    std::fs::write(&p, scene_vox()).unwrap();
    assert!(matches!(
        load_mesh(&p),
        Err(LoadError::UnsupportedFormat { .. })
    ));
    let e = load_model(&dir.path().join("absent.obj")).unwrap_err();
    assert!(matches!(e, LoadError::Io { .. }) && e.to_string().contains("absent.obj"));
    assert_eq!(Format::sniff(b"SSBVBRAW 1 1 1\n"), Some(Format::Raw));
    assert_eq!(Format::sniff(b"  {\"asset\":{}}"), Some(Format::Gltf));
    assert_eq!(
        Format::sniff(b"# comment\n\nmtllib x.mtl\n"),
        Some(Format::Obj)
    );
    assert_eq!(Format::sniff(b"hello world"), None);
}

// ---------------------------------------------------------------------------------------
// Property-based: arbitrary and mutated bytes never panic, errors always name the file.

fn small_inputs() -> Vec<(Vec<u8>, Format)> {
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64(&triangle_buffer())
    );
    vec![
        (ASCII_PLY.as_bytes().to_vec(), Format::Ply),
        (binary_ply(true), Format::Ply),
        (b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nusemtl a\nf 1/1/1 2/1/1 -1/1/1\n".to_vec(), Format::Obj),
        (triangle_gltf_json(Some(&uri), "", 4).into_bytes(), Format::Gltf),
        (textured_glb(), Format::Glb),
        (scene_vox(), Format::Vox),
        (b"SSBVBRAW 2 1 1\n\x01\x00".to_vec(), Format::Raw),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, .. ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512), f in 0usize..6) {
        let format = [Format::Obj, Format::Ply, Format::Gltf, Format::Glb, Format::Vox, Format::Raw][f];
        if let Err(e) = parse(&bytes, format, "p.bin") {
            prop_assert!(e.to_string().starts_with("p.bin"));
        }
    }

    #[test]
    fn mutated_fixtures_never_panic(
        which in 0usize..7,
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
        cut in any::<prop::sample::Index>(),
    ) {
        let (mut bytes, format) = small_inputs().swap_remove(which);
        for (at, value) in edits {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        let keep = cut.index(bytes.len() + 1).max(bytes.len() / 2);
        bytes.truncate(keep);
        if let Err(e) = parse(&bytes, format, "m.bin") {
            prop_assert!(e.to_string().starts_with("m.bin"));
        }
    }
}
