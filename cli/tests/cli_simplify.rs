//! `meshpyr simplify` as a user runs it.

mod common;

use common::{data_arg as data, meshpyr, ok, scratch};
use meshpyr::io::read_mesh;
use meshpyr::mesh::{Attribute, AttributeData, Mesh};
use std::path::Path;

#[test]
fn faces_ratio_and_error_targets() {
    let input = read_mesh(Path::new(&data("bunny.ply"))).unwrap();
    let out = scratch("cli-simplify", "bunny-1000.ply");
    ok(&meshpyr(&[
        "-q",
        "simplify",
        &data("bunny.ply"),
        "-o",
        out.to_str().unwrap(),
        "--faces",
        "1000",
    ]));
    let m = read_mesh(&out).unwrap();
    assert!(
        m.n_faces() <= 1000 && m.n_faces() >= 990,
        "{} faces",
        m.n_faces()
    );
    // Every output vertex is an input vertex (original positions kept), closed and valid.
    let built = Mesh::from_polygons(&m).unwrap();
    built.mesh.validate().unwrap();
    assert!(built.report.input_was_manifold() && !built.report.repaired_anything());
    assert_eq!(built.mesh.topology().boundary_loops, 0);
    let inputs: std::collections::HashSet<[u64; 3]> = input
        .positions
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect();
    assert!(
        m.positions
            .iter()
            .all(|p| inputs.contains(&p.to_array().map(f64::to_bits)))
    );

    let out = scratch("cli-simplify", "bunny-ratio.obj");
    ok(&meshpyr(&[
        "simplify",
        &data("bunny.ply"),
        "-o",
        out.to_str().unwrap(),
        "--ratio",
        "0.1",
    ]));
    let m = read_mesh(&out).unwrap();
    let want = (0.1 * input.n_faces() as f64).round() as usize;
    assert!(m.n_faces() <= want && m.n_faces() + 2 >= want);

    let coarse = scratch("cli-simplify", "bunny-err-coarse.ply");
    let fine = scratch("cli-simplify", "bunny-err-fine.ply");
    ok(&meshpyr(&[
        "-q",
        "simplify",
        &data("bunny.ply"),
        "-o",
        coarse.to_str().unwrap(),
        "--error",
        "0.002",
    ]));
    ok(&meshpyr(&[
        "-q",
        "simplify",
        &data("bunny.ply"),
        "-o",
        fine.to_str().unwrap(),
        "--error",
        "0.0002",
    ]));
    let (c, f) = (read_mesh(&coarse).unwrap(), read_mesh(&fine).unwrap());
    assert!(c.n_faces() < f.n_faces() && f.n_faces() < input.n_faces());
}

#[test]
fn attributes_are_carried_along() {
    // A per-vertex attribute equal to the vertex index: after simplification each output
    // vertex must carry the index of the input vertex whose position it has.
    let mut input = read_mesh(Path::new(&data("nefertiti.ply"))).unwrap();
    let n = input.n_vertices();
    input.vertex_attributes.push(Attribute {
        name: "quality".into(),
        data: AttributeData::F64((0..n).map(|i| i as f64).collect()),
    });
    let src = scratch("cli-simplify", "nefertiti-attr.ply");
    meshpyr::io::write_mesh(&src, &input).unwrap();
    let out = scratch("cli-simplify", "nefertiti-attr-out.ply");
    ok(&meshpyr(&[
        "-q",
        "simplify",
        src.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--faces",
        "100",
    ]));
    let m = read_mesh(&out).unwrap();
    assert!(m.n_faces() <= 100);
    let q = m.vertex_attribute("quality").expect("attribute kept");
    for (i, p) in m.positions.iter().enumerate() {
        let row = q.data.get_f64(i) as usize;
        assert_eq!(input.positions[row], *p);
    }
}

#[test]
fn dirty_input_simplifies() {
    let out = scratch("cli-simplify", "spider.ply");
    ok(&meshpyr(&[
        "-q",
        "simplify",
        &data("spider_assimp.ply"),
        "-o",
        out.to_str().unwrap(),
        "--ratio",
        "0.2",
    ]));
    let m = read_mesh(&out).unwrap();
    assert!(m.n_faces() <= 300, "{} faces", m.n_faces());
    Mesh::from_polygons(&m).unwrap().mesh.validate().unwrap();
}

#[test]
fn errors_exit_non_zero_with_one_line() {
    let out = scratch("cli-simplify", "never.ply");
    let o = out.to_str().unwrap();
    for args in [
        vec!["simplify", data("joint.ply").leak() as &str, "-o", o],
        vec![
            "simplify",
            data("joint.ply").leak(),
            "-o",
            o,
            "--ratio",
            "1.5",
        ],
        vec![
            "simplify",
            data("joint.ply").leak(),
            "-o",
            o,
            "--error",
            "-1",
        ],
        vec![
            "simplify",
            data("joint.ply").leak(),
            "-o",
            o,
            "--faces",
            "10",
            "--ratio",
            "0.5",
        ],
        vec!["simplify", "/nonexistent/x.ply", "-o", o, "--faces", "10"],
    ] {
        let r = meshpyr(&args);
        assert!(!r.status.success(), "{args:?} succeeded");
        assert!(!out.exists());
    }
    let r = meshpyr(&["simplify", &data("joint.ply"), "-o", o, "--ratio", "1.5"]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.starts_with("error: ") && err.contains("ratio") && err.trim_end().lines().count() == 1,
        "{err}"
    );
}

/// A target below the floor of the mesh's topology: the command does what it can, writes the
/// result and says in one warning line where it stopped and why; a reachable target is quiet.
#[test]
fn a_target_below_the_topology_floor_warns_once() {
    let out = scratch("cli-simplify", "elephant-10.ply");
    let run = meshpyr(&[
        "simplify",
        &data("elephant_holes.ply"),
        "-o",
        out.to_str().unwrap(),
        "--faces",
        "10",
    ]);
    ok(&run);
    let stderr = String::from_utf8_lossy(&run.stderr);
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    let w = warnings[0];
    assert!(w.contains("elephant_holes.ply: stopped at"), "{w}");
    assert!(w.contains("no legal collapse left"), "{w}");
    assert!(
        w.contains("the floor of its topology is 318 vertices (1 component, 106 holes, genus 3)"),
        "{w}"
    );
    let m = read_mesh(&out).unwrap();
    assert!(m.n_vertices() <= 2 * 318, "{}", m.n_vertices());

    let run = meshpyr(&[
        "simplify",
        &data("elephant_holes.ply"),
        "-o",
        out.to_str().unwrap(),
        "--ratio",
        "0.2",
    ]);
    ok(&run);
    assert!(!String::from_utf8_lossy(&run.stderr).contains("warning"));
}

/// Closed genus-0 scans go down to a tetrahedron.
#[test]
fn a_marching_cubes_scan_simplifies_to_a_tetrahedron() {
    let out = scratch("cli-simplify", "mc-4.ply");
    let run = meshpyr(&[
        "simplify",
        &data("mc/mc_bunny_quant36.ply"),
        "-o",
        out.to_str().unwrap(),
        "--faces",
        "4",
    ]);
    ok(&run);
    assert!(!String::from_utf8_lossy(&run.stderr).contains("warning"));
    let m = read_mesh(&out).unwrap();
    assert_eq!((m.n_vertices(), m.n_faces()), (4, 4));
}

/// `--prune` drops floating debris before simplifying, says how much, and the ratio still
/// counts the file's triangles; without it every component is kept.
#[test]
fn prune_drops_small_pieces_on_request_only() {
    let input = data("mc/mc_implicit_n56.ply");
    let faces = read_mesh(Path::new(&input)).unwrap().n_triangles();
    let out = scratch("cli-simplify", "implicit-pruned.ply");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "simplify",
            &input,
            "-o",
            out.to_str().unwrap(),
            "--ratio",
            "0.05",
        ];
        args.extend_from_slice(extra);
        let r = meshpyr(&args);
        ok(&r);
        let m = Mesh::from_polygons(&read_mesh(&out).unwrap()).unwrap().mesh;
        (String::from_utf8_lossy(&r.stderr).into_owned(), m)
    };
    let (said, pruned) = run(&["--prune", "0.1"]);
    assert!(said.contains("pruned 27 of 29 components"), "{said}");
    assert_eq!(pruned.topology().components, 2);
    let target = (0.05 * faces as f64).round() as usize;
    assert!(pruned.n_faces() <= target && pruned.n_faces() + 10 >= target);
    let (said, kept) = run(&[]);
    assert!(!said.lines().any(|l| l.starts_with("pruned")), "{said}");
    assert_eq!(kept.topology().components, 29);
}
