//! OBJ (+ MTL) fixtures and errors.

use ssbvb_voxel::load::{
    Format, LoadError, LoadOptions, load_model, load_model_with, srgb_to_linear,
};

use crate::{approx, assert_mesh_invariants, mesh_of, parse, parse_err};

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
