//! Gzip-compressed meshes (`scan.ply.gz`): read and write through the extension, corrupt or
//! truncated streams are one-line errors, and the compressed output is deterministic.

mod common;

use common::*;
use meshpyr::io::{self, IoError, MeshFormat, gunzip, gzip, read_mesh, write_mesh};
use std::path::Path;

#[test]
fn format_comes_from_the_extension_before_gz() {
    let f = |p: &str| MeshFormat::from_path(Path::new(p));
    assert_eq!(f("scan.ply.gz").unwrap(), MeshFormat::Ply);
    assert_eq!(f("A.OBJ.GZ").unwrap(), MeshFormat::Obj);
    assert_eq!(f("dir.off/x.stl.gz").unwrap(), MeshFormat::Stl);
    for bad in ["scan.gz", "scan.tar.gz", ".gz", "scan.ply.zip"] {
        assert!(
            matches!(f(bad), Err(IoError::UnknownFormat { .. })),
            "{bad}"
        );
    }
}

#[test]
fn compressed_files_read_like_the_plain_ones() {
    for name in [
        "bunny.ply",
        "cone20.off",
        "cube_degenerate_om.obj",
        "spider_assimp.stl",
    ] {
        let plain = read_mesh(data(name)).unwrap();
        let gz = scratch("io_gzip", &format!("{name}.gz"));
        std::fs::write(&gz, gzip(&data_bytes(name))).unwrap();
        assert_eq!(read_mesh(&gz).unwrap(), plain, "{name}");
    }
}

#[test]
fn writing_gz_compresses_deterministically_and_round_trips() {
    let m = read_mesh(data("bunny.ply")).unwrap();
    let a = scratch("io_gzip", "a.ply.gz");
    let b = scratch("io_gzip", "b.ply.gz");
    write_mesh(&a, &m).unwrap();
    write_mesh(&b, &m).unwrap();
    let (ba, bb) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert_eq!(ba, bb);
    assert_eq!(&ba[..2], &[0x1f, 0x8b]);
    let plain = io::write_mesh_bytes(&m, MeshFormat::Ply, &Default::default()).unwrap();
    assert!(ba.len() < plain.len());
    assert_eq!(gunzip(&ba).unwrap(), plain);
    assert_eq!(read_mesh(&a).unwrap(), m);
}

#[test]
fn concatenated_members_are_one_stream() {
    let text = data_bytes("tetrahedron.off");
    let (head, tail) = text.split_at(text.len() / 2);
    let mut two = gzip(head);
    two.extend(gzip(tail));
    assert_eq!(gunzip(&two).unwrap(), text);
}

#[test]
fn corrupt_truncated_and_mislabelled_gz_are_one_line_errors() {
    let good = gzip(&data_bytes("bunny.ply"));
    let path = scratch("io_gzip", "bad.ply.gz");
    let mut flipped = good.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x55;
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("truncated", good[..good.len() / 2].to_vec()),
        ("flipped", flipped),
        ("plain", data_bytes("bunny.ply")),
        ("empty", Vec::new()),
    ];
    for (what, bytes) in cases {
        std::fs::write(&path, &bytes).unwrap();
        let e = read_mesh(&path).expect_err(what).to_string();
        assert!(!e.contains('\n'), "{what}: {e}");
        assert!(e.contains("bad.ply.gz"), "{what}: {e}");
    }
    // Every prefix of a small compressed file fails cleanly or, for the complete one, parses.
    let small = gzip(&data_bytes("tetrahedron.off"));
    for n in 0..small.len() {
        assert!(gunzip(&small[..n]).is_err(), "prefix {n}");
    }
    assert!(gunzip(&small).is_ok());
}
