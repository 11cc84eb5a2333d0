//! Atomic writes: the old file survives every failure, no temporary files are left behind.

mod common;

use std::path::Path;

use common::*;
use glam::DVec3;
use meshpyr::io::{IoError, write_atomic, write_mesh};
use meshpyr::mesh::PolygonMesh;

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn write_atomic_creates_and_replaces() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.bin");
    write_atomic(&p, b"first").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"first");
    write_atomic(&p, b"second, longer").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"second, longer");
    write_atomic(&p, b"").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"");
    assert_eq!(entries(dir.path()), ["a.bin"]);
}

#[test]
fn rejected_mesh_leaves_the_old_file_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m.ply");
    let good = rich_mesh();
    write_mesh(&p, &good).unwrap();
    let before = std::fs::read(&p).unwrap();
    let mut bad = PolygonMesh::from_triangles(vec![DVec3::ZERO; 3], &[[0, 1, 2]]);
    bad.face_indices[1] = 99;
    let e = write_mesh(&p, &bad).unwrap_err();
    assert!(matches!(e, IoError::InvalidMesh { .. }), "{e}");
    assert!(
        e.to_string()
            .starts_with(&format!("{}: cannot write PLY: ", p.display())),
        "{e}"
    );
    assert_eq!(std::fs::read(&p).unwrap(), before);
    assert_eq!(entries(dir.path()), ["m.ply"]);
}

#[test]
fn rename_onto_a_directory_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.obj");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), b"x").unwrap();
    let e = write_mesh(&target, &rich_mesh()).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }), "{e}");
    assert!(target.is_dir());
    assert_eq!(std::fs::read(target.join("keep")).unwrap(), b"x");
    assert_eq!(
        entries(dir.path()),
        ["out.obj"],
        "temporary file left behind"
    );
}

#[test]
fn missing_directory_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("no/such/dir/m.stl");
    let e = write_mesh(&p, &rich_mesh()).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }), "{e}");
    assert!(!e.to_string().contains('\n'));
}

#[test]
fn unknown_extension_is_rejected_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m.xyz");
    assert!(matches!(
        write_mesh(&p, &rich_mesh()),
        Err(IoError::UnknownFormat { .. })
    ));
    assert!(entries(dir.path()).is_empty());
}

#[test]
fn relative_path_in_current_directory() {
    // A bare file name has an empty parent: the temp file must go to ".".
    let dir = tempfile::tempdir().unwrap();
    let old = std::env::current_dir().unwrap();
    std::env::set_current_dir(dir.path()).unwrap();
    let r = write_atomic(Path::new("bare.txt"), b"ok");
    std::env::set_current_dir(old).unwrap();
    r.unwrap();
    assert_eq!(std::fs::read(dir.path().join("bare.txt")).unwrap(), b"ok");
}
