//! The streaming split against the one-process builder and quadrics: generated scans split
//! into many small cells through tiny buffers and a sample smaller than the mesh.

use super::*;
use crate::io::PlyEncoding;
use crate::mesh::{CornerTable, Materials, PolygonMesh};
use crate::pm::decimate::{FlatMesh, initial_quadrics};
use crate::pm::partition::contents;
use glam::DVec3;
use std::path::Path;

const BOUNDARY_WEIGHT: f64 = 10.0;

/// A height-field scan of `nx × ny` vertices, quads and triangles mixed, with a quad whose
/// triangulation has a repeated vertex (dropped, as the builder drops it).
fn scan(nx: u32, ny: u32) -> PolygonMesh {
    let positions = (0..nx * ny)
        .map(|i| {
            let (x, y) = ((i % nx) as f64, (i / nx) as f64);
            DVec3::new(x * 0.1, y * 0.1, 0.05 * (x * 0.7).sin() * (y * 0.4).cos())
        })
        .collect();
    let mut m = PolygonMesh::from_triangles(positions, &[]);
    for y in 0..ny - 1 {
        for x in 0..nx - 1 {
            let v = y * nx + x;
            let (a, b, c, d) = (v, v + 1, v + nx + 1, v + nx);
            if (x + y) % 3 == 0 {
                m.push_face(&[a, b, c, d]);
            } else {
                m.push_face(&[a, b, c]);
                m.push_face(&[a, c, d]);
            }
        }
    }
    m.push_face(&[0, 1, 1]);
    m
}

/// `scan` with a wall standing on a row of it: a second sheet sharing nine edges with the
/// first (three triangles each), the row's vertices split into a copy per sheet.
fn scan_with_a_wall(nx: u32, ny: u32) -> PolygonMesh {
    let mut m = scan(nx, ny);
    let row: Vec<u32> = (0..nx - 2).map(|x| (ny / 2) * nx + x + 1).collect();
    let up: Vec<u32> = row
        .iter()
        .map(|&v| {
            let p = m.positions[v as usize];
            vertex(&mut m, p + DVec3::new(0.0, 0.02, 0.3))
        })
        .collect();
    for k in 0..row.len() - 1 {
        m.push_face(&[row[k], row[k + 1], up[k + 1]]);
        m.push_face(&[row[k], up[k + 1], up[k]]);
    }
    m
}

/// Adds a vertex at `p`, returning its index.
fn vertex(m: &mut PolygonMesh, p: DVec3) -> u32 {
    m.positions.push(p);
    (m.positions.len() - 1) as u32
}

/// `scan` with non-manifold spots: "books" of three one-triangle pages on a spine of two grid
/// vertices (three triangles on one edge, the first page split off at both ends), and single
/// triangles hanging from a grid vertex by one corner (a second fan there), their triangles
/// spread through the face list so that first corners interleave.
fn scan_with_fans_and_books(nx: u32, ny: u32) -> PolygonMesh {
    let grid = scan(nx, ny);
    let mut m = PolygonMesh::from_triangles(grid.positions.clone(), &[]);
    let polys: Vec<Vec<u32>> = grid.faces().map(|f| f.to_vec()).collect();
    let mut extra: Vec<Vec<u32>> = Vec::new();
    for k in 0..12u32 {
        let a = (3 + 5 * k) % (nx - 2) + 1 + ((7 * k) % (ny - 2) + 1) * nx;
        let b = a + 1;
        let (pa, pb) = (m.positions[a as usize], m.positions[b as usize]);
        let mid = 0.5 * (pa + pb);
        let up = vertex(&mut m, mid + DVec3::new(0.0, 0.03, 0.2));
        let side = vertex(&mut m, mid + DVec3::new(0.0, -0.2, 0.1));
        let low = vertex(&mut m, mid + DVec3::new(0.0, 0.1, -0.2));
        // The spine is a grid edge only when a and b are not on the same grid triangle pair
        // already: keep the books off the grid by giving them their own spine copy.
        let (s0, s1) = (vertex(&mut m, pa + DVec3::Z), vertex(&mut m, pb + DVec3::Z));
        let lift = DVec3::Z;
        m.positions[up as usize] += lift;
        m.positions[side as usize] += lift;
        m.positions[low as usize] += lift;
        extra.push(vec![s0, s1, up]);
        extra.push(vec![s1, s0, side]);
        extra.push(vec![s0, s1, low]);
        let hang = (11 * k + 2) % (nx - 2) + 1 + ((3 * k + 1) % (ny - 2) + 1) * nx;
        let p = m.positions[hang as usize];
        let h1 = vertex(&mut m, p + DVec3::new(0.03, 0.0, 0.1));
        let h2 = vertex(&mut m, p + DVec3::new(0.0, 0.03, 0.1));
        extra.push(vec![hang, h1, h2]);
    }
    let every = polys.len() / (extra.len() + 1);
    let mut extra = extra.into_iter();
    for (i, p) in polys.iter().enumerate() {
        m.push_face(p);
        if i % every == every - 1
            && let Some(e) = extra.next()
        {
            m.push_face(&e);
        }
    }
    for e in extra {
        m.push_face(&e);
    }
    m
}

fn write_ply(path: &Path, m: &PolygonMesh, encoding: PlyEncoding) {
    let bytes = crate::io::ply::write(m, &Materials::default(), encoding).unwrap();
    std::fs::write(path, bytes).unwrap();
}

fn small(block: usize) -> SplitOptions {
    sampled(block, 300)
}

fn sampled(block: usize, sample_size: usize) -> SplitOptions {
    SplitOptions {
        block_vertices: block,
        buffer_bytes: 64,
        sample_size,
    }
}

/// The pieces' faces and records, all cells together.
fn pieces_of(pieces: &[std::path::PathBuf]) -> (Vec<[u32; 3]>, Vec<contents::Record>) {
    let (mut faces, mut records) = (Vec::new(), Vec::new());
    for p in pieces {
        let (f, r) = contents::read_piece(p).unwrap();
        faces.extend(f);
        records.extend(r);
    }
    (faces, records)
}

/// Splits `m` written as `encoding`, runs the cell tasks, and checks the pieces against the
/// one-process corner table and quadrics, bit for bit; returns the number of cells.
fn check_against_one_process(m: &PolygonMesh, block: usize, encoding: PlyEncoding) -> usize {
    check_sampled(m, small(block), encoding)
}

/// [`check_against_one_process`] with the given split options.
fn check_sampled(m: &PolygonMesh, options: SplitOptions, encoding: PlyEncoding) -> usize {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scan.ply");
    write_ply(&input, m, encoding);
    let cells = dir.path().join("cells");
    std::fs::create_dir(&cells).unwrap();
    let manifest = split_into_cells(&input, &cells, &options).unwrap();
    let (pieces, copies) = cell_pieces(&cells, BOUNDARY_WEIGHT, dir.path()).unwrap();

    let read = crate::io::ply::read(&std::fs::read(&input).unwrap()).unwrap();
    let repaired = CornerTable::from_polygons(&read).unwrap();
    let source = &repaired.source.vertex_source;
    assert_eq!(copies.n_vertices, source.len() as u64);
    let positions = source.iter().map(|&s| read.positions[s as usize]).collect();
    let flat = FlatMesh::from_corners(positions, &repaired.corners);
    let quadrics = initial_quadrics(&flat, BOUNDARY_WEIGHT);

    let (mut faces, mut records) = pieces_of(&pieces);
    let mut want = flat.triangles();
    assert_eq!(faces.len(), want.len(), "each triangle in one piece");
    faces.sort_unstable();
    want.sort_unstable();
    assert_eq!(faces, want);
    records.sort_by_key(|r| r.vertex);
    let vertices: Vec<u32> = records.iter().map(|r| r.vertex).collect();
    assert_eq!(
        vertices,
        flat.survivors(),
        "each vertex with faces in one piece"
    );
    let bits = |q: &crate::pm::quadric::Quadric| {
        q.a.iter()
            .chain(&q.b)
            .chain([&q.c, &q.weight])
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    for r in &records {
        let v = r.vertex;
        let p = flat.position(v);
        assert_eq!(
            r.position.to_array().map(f64::to_bits),
            p.to_array().map(f64::to_bits)
        );
        assert_eq!(
            bits(&r.quadric.planes),
            bits(&quadrics.faces[v as usize]),
            "vertex {v}"
        );
        assert_eq!(
            r.quadric.rim.as_ref().map(bits),
            quadrics.rim(v).map(bits),
            "rim {v}"
        );
    }
    assert_eq!(manifest.input_vertices, read.positions.len() as u64);
    manifest.cells.len()
}

#[test]
fn a_clean_scan_in_many_cells_gives_the_one_process_triangles_and_quadrics_bit_for_bit() {
    let cells = check_against_one_process(&scan(40, 30), 50, PlyEncoding::BinaryLittleEndian);
    assert!(cells >= 32, "{cells} cells");
}

#[test]
fn real_scans_in_many_cells_give_the_one_process_triangles_and_quadrics_bit_for_bit() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    for name in ["bunny.ply", "fandisk.ply", "elephant_holes.ply"] {
        let m = crate::io::ply::read(&std::fs::read(data.join(name)).unwrap()).unwrap();
        let block = m.positions.len() / 40;
        let cells = check_sampled(&m, sampled(block, 2000), PlyEncoding::BinaryLittleEndian);
        assert!(cells >= 32, "{name}: {cells} cells");
    }
}

#[test]
fn fans_and_non_manifold_edges_across_cells_are_repaired_as_the_builder_repairs_them() {
    let m = scan_with_fans_and_books(36, 30);
    let report = CornerTable::from_polygons(&m).unwrap().report;
    assert!(report.non_manifold_edges >= 12, "{report:?}");
    assert!(report.split_vertices >= 24, "{report:?}");
    assert_eq!(
        report.flipped_faces + report.detached_vertices,
        0,
        "{report:?}"
    );
    for encoding in [PlyEncoding::Ascii, PlyEncoding::BinaryBigEndian] {
        let cells = check_against_one_process(&m, 40, encoding);
        assert!(cells >= 32, "{cells} cells");
    }
}

#[test]
fn a_wall_sharing_a_row_of_edges_across_many_cells_is_repaired_as_the_builder_repairs_it() {
    let m = scan_with_a_wall(40, 24);
    let report = CornerTable::from_polygons(&m).unwrap().report;
    assert!(report.non_manifold_edges >= 30, "{report:?}");
    assert_eq!(
        report.flipped_faces + report.detached_vertices,
        0,
        "{report:?}"
    );
    let cells = check_against_one_process(&m, 30, PlyEncoding::BinaryLittleEndian);
    assert!(cells >= 32, "{cells} cells");
}

/// The bytes of every file of a folder, by name.
fn folder(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let name = e.file_name().to_string_lossy().into_owned();
            (name, std::fs::read(e.path()).unwrap())
        })
        .collect();
    out.sort();
    out
}

#[test]
fn ascii_and_binary_files_and_any_buffer_give_the_same_bytes_every_time() {
    let m = scan_with_fans_and_books(30, 20);
    let dir = tempfile::tempdir().unwrap();
    let split = |name: &str, encoding, buffer| {
        let input = dir.path().join(format!("{name}.ply"));
        write_ply(&input, &m, encoding);
        let out = dir.path().join(name);
        std::fs::create_dir(&out).unwrap();
        let options = SplitOptions {
            buffer_bytes: buffer,
            ..small(30)
        };
        split_into_cells(&input, &out, &options).unwrap();
        folder(&out)
    };
    let first = split("a", PlyEncoding::BinaryLittleEndian, 64);
    assert!(first.len() > 3 * 16, "{} files", first.len());
    assert!(first.iter().all(|(n, _)| !n.ends_with(".part")));
    assert_eq!(first, split("b", PlyEncoding::BinaryLittleEndian, 64));
    assert_eq!(first, split("c", PlyEncoding::Ascii, 1 << 20));
    assert_eq!(first, split("d", PlyEncoding::BinaryBigEndian, 100));
}

/// `grid` with the faces `flip` picks reversed.
fn flipped(grid: &PolygonMesh, flip: impl Fn(usize) -> bool) -> PolygonMesh {
    let mut m = PolygonMesh::from_triangles(grid.positions.clone(), &[]);
    for (i, f) in grid.faces().enumerate() {
        let mut f = f.to_vec();
        if flip(i) {
            f.reverse();
        }
        m.push_face(&f);
    }
    m
}

#[test]
fn flipped_patches_across_cells_are_oriented_as_the_builder_orients_them() {
    // Most of the grid (so the builder flips the rest: the majority wins) and a scattering
    // of single faces, across cells, with fans and books about.
    let grid = scan_with_fans_and_books(36, 30);
    let n = grid.n_faces();
    let m = flipped(&grid, |i| (200..n - 200).contains(&i) || i % 37 == 5);
    let report = CornerTable::from_polygons(&m).unwrap().report;
    // The first 200 faces, less the scattered ones among them, are the minority.
    assert!((300..n / 2).contains(&report.flipped_faces), "{report:?}");
    assert_eq!(
        report.orientation_cuts + report.detached_vertices,
        0,
        "{report:?}"
    );
    for encoding in [PlyEncoding::BinaryLittleEndian, PlyEncoding::Ascii] {
        let cells = check_against_one_process(&m, 40, encoding);
        assert!(cells >= 32, "{cells} cells");
    }
}

#[test]
fn a_triangle_doubled_back_to_back_is_refused_as_a_multi_edge_the_builder_detaches() {
    // Its edges have three triangles each; the pairs leave two edges between the same two
    // vertices, which the builder detaches in a loop over the whole mesh.
    let mut m = scan(20, 20);
    let f: Vec<u32> = m.faces().nth(300).unwrap().to_vec();
    m.push_face(&[f[0], f[2], f[1]]);
    let report = CornerTable::from_polygons(&m).unwrap().report;
    assert!(report.detached_vertices > 0, "{report:?}");
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("doubled.ply");
    write_ply(&input, &m, PlyEncoding::BinaryLittleEndian);
    split_into_cells(&input, dir.path(), &small(40)).unwrap();
    let e = cell_pieces(dir.path(), BOUNDARY_WEIGHT, dir.path()).unwrap_err();
    assert!(
        matches!(
            e,
            SplitError::NotLocal {
                repair: GlobalRepair::MultiEdge,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn damaged_inputs_and_cell_files_are_typed_errors_naming_the_file() {
    let m = scan(20, 12);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scan.ply");
    write_ply(&input, &m, PlyEncoding::BinaryLittleEndian);
    let good = std::fs::read(&input).unwrap();
    let cut = dir.path().join("cut.ply");
    std::fs::write(&cut, &good[..good.len() - 5]).unwrap();
    let out = dir.path().join("cells");
    std::fs::create_dir(&out).unwrap();
    let e = split_into_cells(&cut, &out, &small(40)).unwrap_err();
    assert!(matches!(e, SplitError::Read(_)), "{e}");
    assert!(e.to_string().starts_with(&cut.display().to_string()), "{e}");
    assert!(
        folder(&out).is_empty(),
        "a failed split leaves nothing: {:?}",
        folder(&out).iter().map(|x| &x.0).collect::<Vec<_>>()
    );

    let manifest = split_into_cells(&input, &out, &small(40)).unwrap();
    let face = out.join("c1.face");
    let mut bytes = std::fs::read(&face).unwrap();
    bytes[40] ^= 1;
    std::fs::write(&face, &bytes).unwrap();
    let e = cell_fans(&out, &manifest, 1, &Flips::default()).unwrap_err();
    assert!(
        e.to_string().starts_with(&face.display().to_string()),
        "{e}"
    );
    bytes[40] ^= 1;
    std::fs::write(&face, &bytes[..bytes.len() - 1]).unwrap();
    assert!(matches!(
        cell_fans(&out, &manifest, 1, &Flips::default()),
        Err(SplitError::File(_))
    ));
    let e = cell_fans(&out, &manifest, 99, &Flips::default()).unwrap_err();
    assert!(matches!(e, SplitError::File(_)), "{e}");

    let path = out.join("manifest");
    let mut bytes = std::fs::read(&path).unwrap();
    for i in (0..bytes.len()).step_by(5) {
        bytes[i] ^= 0x20;
        std::fs::write(&path, &bytes).unwrap();
        let e = Manifest::read(&path).unwrap_err();
        assert_eq!(e.path, path);
        bytes[i] ^= 0x20;
    }
}

#[test]
fn the_cells_partition_the_vertices_and_follow_the_labels() {
    let m = scan(33, 27);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scan.ply");
    write_ply(&input, &m, PlyEncoding::BinaryLittleEndian);
    let manifest = split_into_cells(&input, dir.path(), &small(45)).unwrap();
    let labels = std::fs::read(dir.path().join("cell_of.u32")).unwrap();
    assert_eq!(labels.len(), 4 * m.positions.len());
    let mut seen = vec![false; m.positions.len()];
    for (k, e) in manifest.cells.iter().enumerate() {
        let [vert, _, _] = files::cell_paths(dir.path(), k);
        for (v, p) in files::read_vertices(&vert, e.vertices, e.crc[0]).unwrap() {
            assert!(!seen[v as usize], "vertex {v} in two cells");
            seen[v as usize] = true;
            assert_eq!(p, m.positions[v as usize]);
            let label = u32::from_le_bytes(labels[4 * v as usize..][..4].try_into().unwrap());
            assert_eq!(label, k as u32);
        }
        // The sample is a third of the mesh: cells stay near the block size (within the
        // sample's error, which the tree's margin covers on average, not for every cell).
        assert!(e.vertices <= 45 + 45 / 4, "cell {k}: {}", e.vertices);
    }
    assert!(seen.iter().all(|&s| s));
    assert_eq!(manifest.sample, (300, 300));
    assert_eq!(manifest.dropped_triangles, 1);
}

#[test]
fn a_hierarchy_built_from_the_cells_replays_every_split_and_leaves_no_file() {
    let m = scan_with_fans_and_books(40, 30);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scan.ply");
    write_ply(&input, &m, PlyEncoding::BinaryLittleEndian);
    let scratch = dir.path().join("scratch");
    let opts = crate::pm::PmOptions {
        block_vertices: Some(100),
        block_scratch: Some(scratch.clone()),
        ..Default::default()
    };
    let (pm, source) = hierarchy_from_cells(&input, &opts, &crate::progress::NoProgress).unwrap();
    let repaired = CornerTable::from_polygons(&m).unwrap();
    assert!(repaired.report.split_vertices > 0);
    assert_eq!(source, repaired.source);
    assert_eq!(pm.n_vertices(), source.vertex_source.len());
    // Its many small components (the books, the hanging triangles) stay in the base.
    assert!(
        pm.n_base_vertices() < pm.n_vertices() / 8,
        "{}",
        pm.n_base_vertices()
    );
    crate::pm::ProgressiveMesh::from_parts(pm.to_parts()).unwrap();
    assert_eq!(
        std::fs::read_dir(&scratch).unwrap().count(),
        0,
        "scratch left"
    );

    let doubled = dir.path().join("doubled.ply");
    let mut f = m.clone();
    let t: Vec<u32> = f.faces().nth(300).unwrap().to_vec();
    f.push_face(&[t[0], t[2], t[1]]);
    write_ply(&doubled, &f, PlyEncoding::BinaryLittleEndian);
    let e = hierarchy_from_cells(&doubled, &opts, &crate::progress::NoProgress).unwrap_err();
    assert!(matches!(e, SplitError::NotLocal { .. }), "{e}");
    assert_eq!(
        std::fs::read_dir(&scratch).unwrap().count(),
        0,
        "scratch left"
    );
}

/// A scan with fans, books and a flipped patch across cells, written as binary PLY and split
/// into cells of 30 in the folder it returns (its `cells` subfolder); the scan's vertex count.
fn flipped_scan_split() -> (tempfile::TempDir, std::path::PathBuf, usize) {
    let m = flipped(&scan_with_fans_and_books(30, 24), |i| {
        (100..500).contains(&i)
    });
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scan.ply");
    write_ply(&input, &m, PlyEncoding::BinaryLittleEndian);
    let cells = dir.path().join("cells");
    std::fs::create_dir(&cells).unwrap();
    split_into_cells(&input, &cells, &small(30)).unwrap();
    (dir, cells, m.n_vertices())
}

#[test]
fn the_pieces_are_the_same_bytes_on_any_number_of_threads() {
    let (dir, cells, _) = flipped_scan_split();
    let pieces_on = |threads: usize| {
        let out = dir.path().join(format!("on{threads}"));
        std::fs::create_dir(&out).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| cell_pieces(&cells, BOUNDARY_WEIGHT, &out).unwrap());
        folder(&out)
    };
    let one = pieces_on(1);
    assert!(one.len() >= 16);
    assert_eq!(one, pieces_on(3));
}

#[test]
fn the_cell_rounds_through_files_write_the_pieces_of_the_rounds_in_memory() {
    let (dir, cells, n_vertices) = flipped_scan_split();
    let pieces_by = |name: &str, in_memory: bool| {
        let out = dir.path().join(name);
        std::fs::create_dir(&out).unwrap();
        let (_, copies) = match in_memory {
            true => super::cell::cell_pieces_in_memory(&cells, BOUNDARY_WEIGHT, &out).unwrap(),
            false => cell_pieces(&cells, BOUNDARY_WEIGHT, &out).unwrap(),
        };
        (folder(&out), copies)
    };
    let (files, copies) = pieces_by("files", false);
    assert!(files.len() >= 16 && copies.n_vertices > n_vertices as u64);
    assert_eq!((files, copies), pieces_by("memory", true));
}

#[test]
fn a_refusal_comes_back_from_the_rounds_as_the_cell_found_it() {
    let mut m = scan(20, 20);
    let f: Vec<u32> = m.faces().nth(300).unwrap().to_vec();
    m.push_face(&[f[0], f[2], f[1]]);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("doubled.ply");
    write_ply(&input, &m, PlyEncoding::BinaryLittleEndian);
    split_into_cells(&input, dir.path(), &small(40)).unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let refused = || {
        let e = cell_pieces(dir.path(), BOUNDARY_WEIGHT, &out).unwrap_err();
        let SplitError::NotLocal { repair, path, .. } = &e else {
            panic!("{e}")
        };
        assert_eq!(*repair, GlobalRepair::MultiEdge);
        assert!(path.to_string_lossy().ends_with(".face"), "{e}");
        e.to_string()
    };
    // The first refusal in cell order, whichever task finished first.
    assert_eq!(refused(), refused());
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0, "pieces left");
}

#[test]
fn the_first_cells_drawn_in_memory_are_the_cells_the_split_writes_from_a_partial_sample() {
    // A sample of a quarter of the vertices: the reservoir replaces points, so its draws, seeded
    // from the counts, must be the same in memory as in the split.
    let m = scan_with_fans_and_books(40, 30);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scan.ply");
    write_ply(&input, &m, PlyEncoding::Ascii);
    let options = sampled(100, m.n_vertices() / 4);
    let manifest = split_into_cells(&input, dir.path(), &options).unwrap();
    assert!(manifest.sample.1 < manifest.input_vertices);
    let labels = std::fs::read(dir.path().join("cell_of.u32")).unwrap();
    let points = super::first::InputPoints {
        positions: &m.positions,
        polygons: m.n_faces() as u64,
        source: None,
    };
    let cells =
        super::first::first_cells_sampled(&points, m.n_vertices(), 100, options.sample_size);
    assert_eq!(cells.n_cells, manifest.cells.len());
    let written: Vec<u32> = labels
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    assert_eq!(cells.cell_of, written);
}
