//! The streaming split of a scan into cell files through the public API
//! (`meshpyr::pm::blocks`, docs/partitioned.md "Splitting a scan into cell files in one pass"):
//! the cells partition a real scan, the hierarchy built from them is a valid one of the
//! repaired scan, the files are the same every time, and damage is a typed error.

use meshpyr::io::read_mesh;
use meshpyr::mesh::Mesh;
use meshpyr::pm::blocks::{
    Manifest, SplitError, SplitOptions, cell_fans, hierarchy_from_cells, split_into_cells,
};
use meshpyr::pm::{PmOptions, ProgressiveMesh};
use meshpyr::progress::NoProgress;
use std::path::Path;

mod common;

fn folder_bytes(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

#[test]
fn the_cells_of_a_scan_hold_each_vertex_once_and_every_triangle_of_the_builder() {
    let input = common::data("bunny.ply");
    let built = Mesh::from_polygons(&read_mesh(&input).unwrap()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let options = SplitOptions {
        buffer_bytes: 256,
        sample_size: 5000,
        ..SplitOptions::new(1000)
    };
    let manifest = split_into_cells(&input, dir.path(), &options).unwrap();
    assert!(manifest.cells.len() >= 32);
    let vertices: u64 = manifest.cells.iter().map(|c| c.vertices).sum();
    assert_eq!(vertices, manifest.input_vertices);
    assert_eq!(manifest.triangles, built.mesh.n_faces() as u64);
    assert_eq!(
        Manifest::read(&dir.path().join("manifest")).unwrap(),
        manifest
    );

    let again = tempfile::tempdir().unwrap();
    split_into_cells(&input, again.path(), &options).unwrap();
    assert_eq!(folder_bytes(dir.path()), folder_bytes(again.path()));
}

#[test]
fn a_hierarchy_from_the_cells_of_a_scan_replays_every_split() {
    let input = common::data("bunny.ply");
    let built = Mesh::from_polygons(&read_mesh(&input).unwrap()).unwrap();
    let scratch = tempfile::tempdir().unwrap();
    let opts = PmOptions {
        block_vertices: Some(2000),
        block_scratch: Some(scratch.path().to_path_buf()),
        ..Default::default()
    };
    let (pm, source) = hierarchy_from_cells(&input, &opts, &NoProgress).unwrap();
    assert_eq!(source, built.source);
    assert_eq!(pm.n_vertices(), built.mesh.n_vertices());
    assert!(pm.n_base_vertices() <= 2000);
    ProgressiveMesh::from_parts(pm.to_parts()).unwrap();
    assert_eq!(std::fs::read_dir(scratch.path()).unwrap().count(), 0);
}

#[test]
fn a_damaged_cell_file_or_input_is_an_error_naming_the_file() {
    let input = common::data("fandisk.ply");
    let dir = tempfile::tempdir().unwrap();
    let manifest = split_into_cells(&input, dir.path(), &SplitOptions::new(300)).unwrap();
    let vert = dir.path().join("c2.vert");
    let mut bytes = std::fs::read(&vert).unwrap();
    bytes[9] ^= 0x40;
    std::fs::write(&vert, &bytes).unwrap();
    let e = cell_fans(dir.path(), &manifest, 2).unwrap_err();
    assert!(matches!(e, SplitError::File(_)), "{e}");
    assert!(
        e.to_string().starts_with(&vert.display().to_string()),
        "{e}"
    );

    let bad = dir.path().join("bad.ply");
    let good = std::fs::read(&input).unwrap();
    std::fs::write(&bad, &good[..good.len() / 2]).unwrap();
    let out = tempfile::tempdir().unwrap();
    let e = split_into_cells(&bad, out.path(), &SplitOptions::new(300)).unwrap_err();
    assert!(matches!(e, SplitError::Read(_)), "{e}");
    assert!(e.to_string().starts_with(&bad.display().to_string()), "{e}");
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0);
}
