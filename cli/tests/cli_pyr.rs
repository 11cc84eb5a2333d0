//! `meshpyr build`, `extract`, and `.pyr` files as input of `filter`/`spectrum`/`edit` and as
//! output of `edit`, run as a user runs them.

mod common;

use common::{data_arg as data, fails_with, meshpyr, ok, scratch_arg};

use meshpyr::io;
use std::path::Path;
use std::process::Output;

/// The two mesh files have the same vertices within 1e-9 of the bounding-box diagonal plus
/// the rounding of their position type (what filtering from stored details promises).
fn assert_same_within_bound(a: &str, b: &str) {
    let (ma, mb) = (
        io::read_mesh(Path::new(a)).unwrap(),
        io::read_mesh(Path::new(b)).unwrap(),
    );
    assert_eq!(ma.face_indices, mb.face_indices, "{a} / {b}");
    let (lo, hi) = ma.positions.iter().fold(
        (glam::DVec3::splat(f64::MAX), glam::DVec3::splat(f64::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let f32_ulp = hi.abs().max(lo.abs()).max_element() * f64::from(f32::EPSILON);
    for (p, q) in ma.positions.iter().zip(&mb.positions) {
        let off = (*p - *q).abs().max_element();
        assert!(
            off <= 1e-9 * (hi - lo).length() + f32_ulp,
            "{a} / {b}: {off:e}"
        );
    }
}

#[test]
fn build_then_extract_gives_back_the_file_byte_for_byte() {
    for name in [
        "joint.ply",
        "cube_quad_poly.ply",
        "spider_assimp.ply",
        "tetrahedron.off",
    ] {
        let pyr = scratch_arg("cli-pyr", &format!("{name}.pyr"));
        let back = scratch_arg("cli-pyr", &format!("back-{name}"));
        let msg = ok(&meshpyr(&["build", &data(name), "-o", &pyr]));
        assert!(msg.contains("bytes/vertex"), "{msg}");
        ok(&meshpyr(&["extract", &pyr, "-o", &back]));
        let a = io::read_mesh(Path::new(&data(name))).unwrap();
        let b = io::read_mesh(Path::new(&back)).unwrap();
        assert_eq!(a, b, "{name}");
        assert_eq!(
            common::position_bits(&a),
            common::position_bits(&b),
            "{name}"
        );
        // Our own writers wrote these test files, so even the bytes come back.
        if name.ends_with(".ply") {
            assert!(
                std::fs::read(data(name)).unwrap() == std::fs::read(&back).unwrap(),
                "{name}"
            );
        }
    }
}

#[test]
fn dirty_scans_build_extract_and_filter_exactly() {
    // Non-manifold edges whose repair needs vertices detached (multi-edges).
    for name in ["snowden_lo.ply", "back_to_back_scad.stl"] {
        let pyr = scratch_arg("cli-pyr", &format!("{name}.pyr"));
        let back = scratch_arg("cli-pyr", &format!("back-{name}"));
        ok(&meshpyr(&["build", &data(name), "-o", &pyr]));
        ok(&meshpyr(&["extract", &pyr, "-o", &back]));
        let a = io::read_mesh(Path::new(&data(name))).unwrap();
        let b = io::read_mesh(Path::new(&back)).unwrap();
        assert_eq!(a.positions.len(), b.positions.len(), "{name}");
        assert_eq!(
            common::position_bits(&a),
            common::position_bits(&b),
            "{name}"
        );
        assert_eq!(a.face_indices, b.face_indices, "{name}");
        // The file's finest faces come from the builder's repairs, not from the polygons as
        // read: filtering it must give the very bytes of filtering the mesh.
        let filtered = |input: &str, out: &str| {
            let out = scratch_arg("cli-pyr", &format!("{out}-{name}.ply"));
            ok(&meshpyr(&[
                "-q",
                "filter",
                input,
                "-o",
                &out,
                "--enhance",
                "300:5000=2",
            ]));
            std::fs::read(out).unwrap()
        };
        assert!(
            filtered(&pyr, "f-pyr") == filtered(&data(name), "f-mesh"),
            "{name}: filter from the .pyr differs from the mesh's"
        );
    }
}

#[test]
fn attributes_survive_build_and_extract() {
    let src = scratch_arg("cli-pyr", "rich.ply");
    io::write_mesh(Path::new(&src), &common::rich_mesh()).unwrap();
    let pyr = scratch_arg("cli-pyr", "rich.pyr");
    let back = scratch_arg("cli-pyr", "rich-back.ply");
    ok(&meshpyr(&["build", &src, "-o", &pyr]));
    ok(&meshpyr(&["extract", &pyr, "-o", &back]));
    assert!(std::fs::read(&src).unwrap() == std::fs::read(&back).unwrap());
}

#[test]
fn extract_level_and_truncated_files() {
    let pyr = scratch_arg("cli-pyr", "joint-levels.pyr");
    ok(&meshpyr(&["-q", "build", &data("joint.ply"), "-o", &pyr]));
    let out = scratch_arg("cli-pyr", "joint-60.ply");
    ok(&meshpyr(&[
        "-q", "extract", &pyr, "-o", &out, "--level", "60",
    ]));
    assert_eq!(io::read_mesh(Path::new(&out)).unwrap().n_vertices(), 60);
    fails_with(
        &meshpyr(&["-q", "extract", &pyr, "-o", &out, "--level", "100000"]),
        "outside this file's levels",
    );

    let bytes = std::fs::read(&pyr).unwrap();
    // Cut inside the split blocks: the last complete level, with a warning.
    let cut = scratch_arg("cli-pyr", "joint-cut.pyr");
    let splits = meshpyr::format::container::Container::parse(&bytes)
        .unwrap()
        .entry(*b"SPLT")
        .unwrap();
    let inside = (splits.offset + splits.length / 2) as usize;
    std::fs::write(&cut, &bytes[..inside]).unwrap();
    let w = ok(&meshpyr(&["-q", "extract", &cut, "-o", &out]));
    assert!(w.contains("warning:") && w.contains("truncated"), "{w}");
    assert_eq!(w.lines().count(), 1, "{w}");
    let m = io::read_mesh(Path::new(&out)).unwrap();
    assert!(m.n_vertices() < 221 && m.n_faces() > 0);
    // `view` says so before it serves anything.
    let o = meshpyr(&["-q", "view", &cut, "--no-browser"]);
    fails_with(&o, "truncated");
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    // Cut inside the header: a clean error.
    std::fs::write(&cut, &bytes[..30]).unwrap();
    fails_with(&meshpyr(&["-q", "extract", &cut, "-o", &out]), "truncated");
    // A damaged byte: a checksum error, not a wrong mesh.
    let mut bad = bytes.clone();
    let k = bad.len() - 100;
    bad[k] ^= 0x10;
    std::fs::write(&cut, &bad).unwrap();
    fails_with(&meshpyr(&["-q", "extract", &cut, "-o", &out]), "checksum");
    // Not a .pyr at all.
    fails_with(
        &meshpyr(&["-q", "extract", &data("joint.ply"), "-o", &out]),
        "not a .pyr file",
    );
}

#[test]
fn filter_spectrum_and_edit_read_pyr_like_the_mesh() {
    let pyr = scratch_arg("cli-pyr", "elephant.pyr");
    ok(&meshpyr(&[
        "-q",
        "build",
        &data("elephant_holes.ply"),
        "-o",
        &pyr,
    ]));
    let (a, b) = (
        scratch_arg("cli-pyr", "el-a.ply"),
        scratch_arg("cli-pyr", "el-b.ply"),
    );
    ok(&meshpyr(&[
        "-q",
        "filter",
        &data("elephant_holes.ply"),
        "-o",
        &a,
        "--lowpass",
        "500",
    ]));
    ok(&meshpyr(&[
        "-q",
        "filter",
        &pyr,
        "-o",
        &b,
        "--lowpass",
        "500",
    ]));
    // The stored details are the pyramid's own quantised values: the very same bits.
    assert!(
        std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
        "filter from the .pyr differs from the mesh's"
    );
    // Without stored details the file is analysed again: the very bytes of the mesh's filter.
    let plain = scratch_arg("cli-pyr", "elephant-plain.pyr");
    ok(&meshpyr(&[
        "-q",
        "build",
        &data("elephant_holes.ply"),
        "-o",
        &plain,
        "--no-details",
    ]));
    assert!(std::fs::metadata(&plain).unwrap().len() < std::fs::metadata(&pyr).unwrap().len());
    ok(&meshpyr(&[
        "-q",
        "filter",
        &plain,
        "-o",
        &b,
        "--lowpass",
        "500",
    ]));
    assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap());

    let (ca, cb) = (
        scratch_arg("cli-pyr", "sa.csv"),
        scratch_arg("cli-pyr", "sb.csv"),
    );
    let png = scratch_arg("cli-pyr", "s.png");
    ok(&meshpyr(&[
        "-q",
        "spectrum",
        &data("elephant_holes.ply"),
        "-o",
        &png,
        "--csv",
        &ca,
    ]));
    ok(&meshpyr(&[
        "-q", "spectrum", &pyr, "-o", &png, "--csv", &cb,
    ]));
    // The energies are whole multiples of the step's square, summed exactly either way.
    assert_eq!(std::fs::read(&ca).unwrap(), std::fs::read(&cb).unwrap());
    ok(&meshpyr(&[
        "-q", "spectrum", &plain, "-o", &png, "--csv", &cb,
    ]));
    assert_eq!(std::fs::read(&ca).unwrap(), std::fs::read(&cb).unwrap());

    // edit: mesh output from .pyr input agrees with the mesh's; .pyr output extracts to the
    // very output of the edit.
    let m = io::read_mesh(Path::new(&data("elephant_holes.ply"))).unwrap();
    let p = m.positions[0];
    let mv = format!("{},{},{}:0.01,0.02,0.0", p.x, p.y, p.z);
    let edit = |input: &str, out: &str| {
        ok(&meshpyr(&[
            "-q", "edit", input, "-o", out, "--level", "600", "--move", &mv, "--radius", "0.2",
        ]))
    };
    let (ea, eb, ep, ex) = (
        scratch_arg("cli-pyr", "ea.ply"),
        scratch_arg("cli-pyr", "eb.ply"),
        scratch_arg("cli-pyr", "e.pyr"),
        scratch_arg("cli-pyr", "ex.ply"),
    );
    edit(&data("elephant_holes.ply"), &ea);
    edit(&pyr, &eb);
    edit(&pyr, &ep);
    ok(&meshpyr(&["-q", "extract", &ep, "-o", &ex]));
    assert!(
        std::fs::read(&ea).unwrap() == std::fs::read(&eb).unwrap(),
        "edit from the .pyr differs from the mesh's"
    );
    let rb = std::fs::read(&eb).unwrap();
    assert!(
        rb == std::fs::read(&ex).unwrap(),
        "edit to .pyr then extract differs"
    );
    assert!(rb != std::fs::read(data("elephant_holes.ply")).unwrap());
    // The edited file is a valid hierarchy: filtering it works.
    ok(&meshpyr(&[
        "-q",
        "filter",
        &ep,
        "-o",
        &ex,
        "--lowpass",
        "500",
    ]));
}

#[test]
fn the_relaxation_is_recorded_and_another_one_is_analysed_afresh() {
    let mesh = data("joint.ply");
    let pyr = scratch_arg("cli-pyr", "joint-mcm.pyr");
    ok(&meshpyr(&[
        "-q", "build", &mesh, "-o", &pyr, "--relax", "mcm",
    ]));
    // The file's operator is used without being asked for, like the mesh with --relax mcm.
    let (a, b, c) = (
        scratch_arg("cli-pyr", "jm-a.ply"),
        scratch_arg("cli-pyr", "jm-b.ply"),
        scratch_arg("cli-pyr", "jm-c.ply"),
    );
    let filter = |input: &str, out: &str, relax: &[&str]| {
        let mut args = vec!["-q", "filter", input, "-o", out, "--enhance", "30:221=2"];
        args.extend_from_slice(relax);
        meshpyr(&args)
    };
    ok(&filter(&mesh, &a, &["--relax", "mcm"]));
    ok(&filter(&pyr, &b, &[]));
    ok(&filter(&mesh, &c, &[]));
    assert_same_within_bound(&a, &b);
    assert!(
        std::fs::read(&a).unwrap() != std::fs::read(&c).unwrap(),
        "mcm and second-difference differ"
    );
    // Another operator than the stored details': analysed afresh, and said so.
    let d = scratch_arg("cli-pyr", "jm-d.ply");
    let out = meshpyr(&[
        "filter",
        &pyr,
        "-o",
        &d,
        "--enhance",
        "30:221=2",
        "--relax",
        "second-difference",
    ]);
    ok(&out);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        said.contains("details recomputed") && said.contains("analysed with --relax mcm"),
        "{said}"
    );
    assert!(std::fs::read(&c).unwrap() == std::fs::read(&d).unwrap());
    // The stored ones are used when they fit, and that is said too; the spectrum needs no
    // analysis at all.
    let out = meshpyr(&["filter", &pyr, "-o", &d, "--enhance", "30:221=2"]);
    ok(&out);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("stored details"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let png = scratch_arg("cli-pyr", "jm.png");
    let out = meshpyr(&["spectrum", &pyr, "-o", &png]);
    ok(&out);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        said.contains("stored details") && said.contains("no analysis"),
        "{said}"
    );
    let out = meshpyr(&["spectrum", &pyr, "-o", &png, "--relax", "normal"]);
    ok(&out);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(said.contains("details recomputed"), "{said}");
}

/// Every command that reads a mesh takes a `.pyr` file as the mesh it stores: the same output
/// as from the original file, byte for byte; a damaged `.pyr` is a one-line error.
#[test]
fn mesh_commands_take_pyr_files() {
    let mesh = data("joint.ply");
    let pyr = scratch_arg("cli-pyr", "joint-as-input.pyr");
    ok(&meshpyr(&["build", &mesh, "-o", &pyr]));
    let stdout = |out: Output| {
        ok(&out);
        out.stdout
    };
    // The same mesh facts; the .pyr file also describes its hierarchy's base level.
    let info = |path: &str| -> serde_json::Value {
        serde_json::from_slice(&stdout(meshpyr(&["info", path, "--json"]))).unwrap()
    };
    let (mut of_pyr, of_mesh) = (info(&pyr), info(&mesh));
    let base = of_pyr["pm_base"].take();
    assert!(base.as_str().unwrap().starts_with("base level "), "{base}");
    assert!(of_mesh["pm_base"].is_null());
    assert_eq!(of_pyr, of_mesh);
    for (name, args) in [
        ("convert", vec!["convert"]),
        ("simplify", vec!["simplify", "--ratio", "0.5"]),
        ("smooth", vec!["smooth", "--method", "taubin"]),
        ("subdivide", vec!["subdivide", "--levels", "1"]),
    ] {
        let from_pyr = scratch_arg("cli-pyr", &format!("{name}-from-pyr.ply"));
        let from_mesh = scratch_arg("cli-pyr", &format!("{name}-from-mesh.ply"));
        let run = |input: &str, out: &str| {
            let mut a = vec!["-q", args[0], input];
            if args[0] == "convert" {
                a.push(out);
            } else {
                a.extend(["-o", out]);
            }
            a.extend(&args[1..]);
            ok(&meshpyr(&a));
        };
        run(&pyr, &from_pyr);
        run(&mesh, &from_mesh);
        assert!(
            std::fs::read(&from_pyr).unwrap() == std::fs::read(&from_mesh).unwrap(),
            "{name}: output from the .pyr differs"
        );
    }
    let again = scratch_arg("cli-pyr", "joint-rebuilt.pyr");
    ok(&meshpyr(&["build", &pyr, "-o", &again]));
    assert!(std::fs::read(&again).unwrap() == std::fs::read(&pyr).unwrap());
    let report = String::from_utf8(stdout(meshpyr(&["compare", &pyr, &mesh, "--json"]))).unwrap();
    assert!(report.contains("\"e_v\":0.0"), "{report}");
    // A flipped byte deep in the file: the checksum catches it.
    let mut bytes = std::fs::read(&pyr).unwrap();
    let n = bytes.len();
    bytes[n - 10] ^= 0x40;
    let damaged = scratch_arg("cli-pyr", "joint-damaged.pyr");
    std::fs::write(&damaged, &bytes).unwrap();
    fails_with(&meshpyr(&["info", &damaged]), "cannot load");
}
