//! Format dispatch by extension and by content.

use ssbvb_voxel::load::{Format, LoadError, load_mesh, load_model};

use crate::ply::ASCII_PLY;
use crate::vox::scene_vox;

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
