use super::*;

fn ops() -> Vec<JournalOp> {
    vec![
        JournalOp::Edit {
            object: 0,
            edit: Edit::RemoveSphere {
                center: (0.1, -0.2, 0.3),
                radius: 0.05,
            },
        },
        JournalOp::Edit {
            object: 1,
            edit: Edit::AddBox {
                min: (-0.5, -0.25, 0.0),
                max: (-0.4, 0.0, 0.125),
                color: (0.9, 0.2, 0.1, 1.0),
            },
        },
        JournalOp::Undo,
        JournalOp::Redo,
        JournalOp::Edit {
            object: 1,
            edit: Edit::AddSphere {
                center: (1.0 / 3.0, 0.0, -0.7),
                radius: 0.01,
                color: (0.1, 0.2, 0.3, 1.0),
            },
        },
        JournalOp::Edit {
            object: 0,
            edit: Edit::RemoveBox {
                min: (-1.0, -1.0, -1.0),
                max: (1.0, -0.9, 1.0),
            },
        },
    ]
}

fn written(dir: &Path) -> PathBuf {
    let path = dir.join("m.obj.ssbvb-journal");
    let mut w = JournalWriter::create(&path, 2, 0xfeed).unwrap();
    for op in ops() {
        w.record(&op).unwrap();
    }
    path
}

#[test]
fn a_journal_reads_back_every_operation_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let path = written(dir.path());
    let back = read_journal(&path, 2, 0xfeed).unwrap();
    assert_eq!(back.ops, ops());
    assert_eq!(back.torn, None);
    assert_eq!(back.valid_bytes, std::fs::metadata(&path).unwrap().len());
    assert_eq!(back.valid_bytes as usize, HEADER_BYTES + 6 * RECORD_BYTES);
    // Resuming appends after what was read.
    let mut w = JournalWriter::resume(&path, 2, back.valid_bytes).unwrap();
    w.record(&JournalOp::Undo).unwrap();
    let again = read_journal(&path, 2, 0xfeed).unwrap();
    assert_eq!(again.ops.len(), 7);
    assert_eq!(again.ops[6], JournalOp::Undo);
    // An object the session does not have is refused when writing.
    let bad = JournalOp::Edit {
        object: 2,
        edit: Edit::RemoveSphere {
            center: (0.0, 0.0, 0.0),
            radius: 0.1,
        },
    };
    assert!(w.record(&bad).is_err());
}

#[test]
fn a_torn_last_record_is_dropped_at_every_cut_and_the_rest_kept() {
    let dir = tempfile::tempdir().unwrap();
    let path = written(dir.path());
    let whole = std::fs::read(&path).unwrap();
    let five = HEADER_BYTES + 5 * RECORD_BYTES;
    for keep in 1..RECORD_BYTES {
        std::fs::write(&path, &whole[..five + keep]).unwrap();
        let back = read_journal(&path, 2, 0xfeed).unwrap();
        assert_eq!(back.ops, ops()[..5], "cut at {keep}");
        assert!(
            back.torn.as_ref().unwrap().contains("record 6 of 6"),
            "{back:?}"
        );
        assert_eq!(back.valid_bytes as usize, five);
    }
    // A whole last record with a flipped byte (written out of order) is torn too.
    let mut bytes = whole.clone();
    bytes[five + 20] ^= 1;
    std::fs::write(&path, &bytes).unwrap();
    let back = read_journal(&path, 2, 0xfeed).unwrap();
    assert_eq!(back.ops.len(), 5);
    assert!(back.torn.unwrap().contains("checksum"));
    // The writer's torn record reads as torn, and resuming cuts it off.
    std::fs::write(&path, &whole[..five]).unwrap();
    let mut w = JournalWriter::resume(&path, 2, five as u64).unwrap();
    w.record_torn(&ops()[5], 40).unwrap();
    let back = read_journal(&path, 2, 0xfeed).unwrap();
    assert!(back.torn.is_some());
    let mut w = JournalWriter::resume(&path, 2, back.valid_bytes).unwrap();
    w.record(&ops()[5]).unwrap();
    let back = read_journal(&path, 2, 0xfeed).unwrap();
    assert_eq!((back.ops, back.torn), (ops(), None));
}

#[test]
fn damage_before_the_end_another_model_or_version_is_refused_and_the_file_kept() {
    let dir = tempfile::tempdir().unwrap();
    let path = written(dir.path());
    let whole = std::fs::read(&path).unwrap();
    let corrupt = |bytes: &[u8]| {
        std::fs::write(&path, bytes).unwrap();
        let e = read_journal(&path, 2, 0xfeed).unwrap_err();
        assert_eq!(
            std::fs::read(&path).unwrap(),
            bytes,
            "the file is left as it was"
        );
        e.to_string()
    };
    let mut bytes = whole.clone();
    bytes[HEADER_BYTES + RECORD_BYTES + 30] ^= 4;
    let e = corrupt(&bytes);
    assert!(
        e.contains("record 2 of 6 is corrupt (checksum mismatch)"),
        "{e}"
    );
    // A newer version.
    let mut bytes = whole.clone();
    bytes[8] = 2;
    let e = corrupt(&bytes);
    assert!(e.contains("journal format version 2"), "{e}");
    // Not a journal at all, or an empty file.
    assert!(corrupt(b"v 0 0 0\n").contains("not an ssbvb brush journal"));
    assert!(corrupt(b"").contains("not an ssbvb brush journal"));
    // Another model (key) or another number of objects.
    std::fs::write(&path, &whole).unwrap();
    let e = read_journal(&path, 2, 0xbeef).unwrap_err().to_string();
    assert!(e.contains("written for another model"), "{e}");
    assert!(read_journal(&path, 3, 0xfeed).is_err());
    // A record naming an object the session lacks is corruption, not an index panic.
    let e = read_journal(&path, 1, 0xfeed);
    assert!(e.is_err());
}

#[test]
fn the_model_key_changes_with_the_voxels_and_the_levels() {
    use crate::prepare::prepare_asset;
    use crate::prepare::tests::tetra;
    use crate::progress::NoProgress;
    let (a5, _) = prepare_asset(&tetra(), 5, &NoProgress).unwrap();
    let (a4, _) = prepare_asset(&tetra(), 4, &NoProgress).unwrap();
    assert_eq!(model_key(&[&a5]), model_key(&[&a5.clone()]));
    assert_ne!(model_key(&[&a5]), model_key(&[&a4]));
    assert_ne!(model_key(&[&a5]), model_key(&[&a5, &a5]));
    let mut moved = a5.clone();
    let last = moved.lods.len() - 1;
    moved.lods[last].point_cloud.voxels[0].color ^= 1;
    assert_ne!(model_key(&[&a5]), model_key(&[&moved]));
}
