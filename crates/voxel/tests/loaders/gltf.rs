//! glTF / GLB fixtures (node transforms, data URIs, strips, sparse accessors, embedded
//! textures) and errors.

use std::path::Path;

use glam::Vec3;
use ssbvb_voxel::load::{Format, LoadError, LoadOptions, load_from_bytes, load_mesh};

use crate::{assert_mesh_invariants, base64, mesh_of, mutate_and_parse, parse, parse_err};

/// One triangle (+ a fourth vertex for strips), u16 indices, normals; returns the buffer.
pub(crate) fn triangle_buffer() -> Vec<u8> {
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

pub(crate) fn triangle_gltf_json(buffer_uri: Option<&str>, extra_nodes: &str, mode: u32) -> String {
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
pub(crate) fn textured_glb() -> Vec<u8> {
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
