//! Bad input as a new user gives it: files that hold no mesh, point clouds, outputs that cannot
//! be written, reversed bands, moves that reach nothing, absurd subdivision levels. Each is a
//! one-line error (or a warning) that names the file and what is wrong, with a non-zero exit
//! code for errors, and nothing written.

mod common;

use common::{data_arg as data, fails_alone_with, meshpyr, ok, stderr};
use std::path::{Path, PathBuf};

/// A fresh folder for one test.
fn folder(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("meshpyr-bad-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).display().to_string()
}

/// The files in `dir`, hidden ones included.
fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

const POINT_CLOUD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                           property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";

/// Every command that needs a surface, on `input`, with its output (if any) in `dir`.
fn every_command(input: &str, dir: &Path) -> Vec<Vec<String>> {
    let lists: [&[&str]; 8] = [
        &["filter", input, "-o", "f.ply", "--lowpass", "10"],
        &["build", input, "-o", "b.pyr"],
        &["simplify", input, "-o", "s.ply", "--ratio", "0.5"],
        &["smooth", input, "-o", "m.ply"],
        &["spectrum", input, "-o", "p.png"],
        &["subdivide", input, "-o", "d.ply"],
        &[
            "edit",
            input,
            "-o",
            "e.ply",
            "--level",
            "3",
            "--move",
            "0,0,0:0,1,0",
            "--radius",
            "1",
        ],
        &["compare", input, input],
    ];
    lists
        .iter()
        .map(|l| {
            // Outputs go to `dir`.
            let mut v: Vec<String> = l.iter().map(|s| s.to_string()).collect();
            if let Some(o) = v.iter().position(|a| a == "-o") {
                v[o + 1] = path(dir, &v[o + 1]);
            }
            v
        })
        .collect()
}

#[test]
fn a_file_without_a_mesh_is_an_error_for_every_command() {
    let dir = folder("nomesh");
    let text = path(&dir, "hello.obj");
    std::fs::write(&text, "hello\nthis is not a mesh\n").unwrap();
    let empty = path(&dir, "empty.obj");
    std::fs::write(&empty, "").unwrap();
    for input in [&text, &empty] {
        let mut commands = every_command(input, &dir);
        commands.push(vec!["info".into(), input.clone()]);
        commands.push(vec!["convert".into(), input.clone(), path(&dir, "c.ply")]);
        for args in commands {
            let out = meshpyr(&args);
            fails_alone_with(
                &out,
                &[input.as_str(), "no mesh in it: no vertices and no faces"],
            );
        }
    }
    assert_eq!(files_in(&dir), ["empty.obj", "hello.obj"]);
}

#[test]
fn a_point_cloud_is_an_error_for_every_command_that_needs_a_surface() {
    let dir = folder("cloud");
    let cloud = path(&dir, "cloud.ply");
    std::fs::write(&cloud, POINT_CLOUD).unwrap();
    for args in every_command(&cloud, &dir) {
        let out = meshpyr(&args);
        fails_alone_with(
            &out,
            &[cloud.as_str(), "3 vertices and no faces (a point cloud)"],
        );
    }
    assert_eq!(files_in(&dir), ["cloud.ply"]);
}

#[test]
fn info_and_convert_take_a_point_cloud() {
    let dir = folder("cloud-ok");
    let cloud = path(&dir, "cloud.ply");
    std::fs::write(&cloud, POINT_CLOUD).unwrap();
    let info = meshpyr(&["info", &cloud]);
    ok(&info);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(text.contains("vertices 3  faces 0"), "{text}");
    assert!(text.contains("no faces: a point cloud"), "{text}");
    let converted = path(&dir, "cloud.obj");
    let said = ok(&meshpyr(&["convert", &cloud, &converted]));
    assert!(said.contains("(3 vertices, 0 faces)"), "{said}");
    assert_eq!(meshpyr::read_mesh(&converted).unwrap().n_vertices(), 3);
}

#[test]
fn the_library_refuses_to_build_on_a_point_cloud() {
    let cloud = meshpyr::PolygonMesh::from_triangles(vec![glam::DVec3::ZERO; 2], &[]);
    let e = meshpyr::Pyramid::build(&cloud).err().unwrap().to_string();
    assert!(e.contains("2 vertices and no faces"), "{e}");
    let target = meshpyr::SimplifyTarget::Ratio(0.5);
    let e = meshpyr::simplify(&cloud, target, &Default::default(), &meshpyr::NoProgress)
        .unwrap_err()
        .to_string();
    assert!(e.contains("2 vertices and no faces"), "{e}");
}

#[test]
fn a_directory_as_input_says_so() {
    let dir = folder("dir-in");
    let name = dir.display().to_string();
    for args in [
        vec!["info", name.as_str()],
        vec!["convert", &name, &path(&dir, "x.ply")],
        vec![
            "filter",
            &name,
            "-o",
            &path(&dir, "x.ply"),
            "--lowpass",
            "9",
        ],
    ] {
        fails_alone_with(&meshpyr(&args), &[&name, "is a directory, not a mesh file"]);
    }
}

#[test]
fn an_output_folder_that_is_missing_or_a_file_fails_before_the_work() {
    let dir = folder("out-folder");
    let missing = path(&dir, "nodir/x.ply");
    let tet = data("tetrahedron.off");
    for args in [
        vec!["convert", tet.as_str(), &missing],
        vec!["smooth", &tet, "-o", &missing],
        vec!["build", &tet, "-o", &path(&dir, "nodir/x.pyr")],
        vec!["spectrum", &tet, "-o", &path(&dir, "nodir/x.png")],
    ] {
        let out = meshpyr(&args);
        fails_alone_with(&out, &["cannot write", "nodir", "does not exist"]);
    }
    // The input itself in place of the folder: not a folder.
    let under_file = format!("{tet}/x.ply");
    fails_alone_with(
        &meshpyr(&["convert", &tet, &under_file]),
        &["cannot write", "is not a folder"],
    );
    fails_alone_with(
        &meshpyr(&["convert", &tet, &dir.display().to_string()]),
        &["cannot write", "it is a directory"],
    );
    assert!(files_in(&dir).is_empty());
}

#[test]
fn pyr_outputs_of_mesh_commands_point_to_build() {
    let dir = folder("pyr-out");
    let tet = data("tetrahedron.off");
    let pyr = path(&dir, "y.pyr");
    for args in [
        vec!["convert", tet.as_str(), &pyr],
        vec!["filter", &tet, "-o", &pyr, "--lowpass", "3"],
    ] {
        fails_alone_with(&meshpyr(&args), &["y.pyr", "`meshpyr build IN -o"]);
    }
}

#[test]
fn spectrum_charts_must_be_named_png() {
    let dir = folder("svg");
    let svg = path(&dir, "spec.svg");
    fails_alone_with(
        &meshpyr(&["spectrum", &data("tetrahedron.off"), "-o", &svg]),
        &["spec.svg", "PNG only"],
    );
    assert!(files_in(&dir).is_empty());
}

#[test]
fn reversed_vertex_bands_are_rejected_with_the_right_order() {
    let dir = folder("band");
    for option in ["--stopband", "--enhance", "--gain"] {
        let band = if option == "--stopband" {
            "5000:1000"
        } else {
            "5000:1000=2"
        };
        let out = meshpyr(&[
            "filter",
            &data("tetrahedron.off"),
            "-o",
            &path(&dir, "f.ply"),
            option,
            band,
        ]);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert!(stderr(&out).contains("write 1000:5000"), "{}", stderr(&out));
    }
}

#[test]
fn a_move_that_reaches_no_vertex_is_a_warning() {
    let dir = folder("far-move");
    let out = meshpyr(&[
        "edit",
        &data("tetrahedron.off"),
        "-o",
        &path(&dir, "e.ply"),
        "--level",
        "4",
        "--move",
        "5,5,5:0,1,0",
        "--radius",
        "0.5",
    ]);
    let err = ok(&out);
    assert!(
        err.contains("warning:") && err.contains("the move at 5,5,5 reaches no vertex of level 4"),
        "{err}"
    );
    // A move that does reach a vertex says nothing of the kind.
    let near = meshpyr(&[
        "edit",
        &data("tetrahedron.off"),
        "-o",
        &path(&dir, "e.ply"),
        "--level",
        "4",
        "--move",
        "1,0,0:0,1,0",
        "--radius",
        "0.5",
    ]);
    assert!(!ok(&near).contains("reaches no vertex"));
}

#[test]
fn subdivision_beyond_the_face_limit_names_the_limit_without_overflow() {
    let dir = folder("subdiv-50");
    let out = meshpyr(&[
        "subdivide",
        &data("tetrahedron.off"),
        "-o",
        &path(&dir, "s.ply"),
        "--levels",
        "50",
    ]);
    fails_alone_with(
        &out,
        &[
            "50 levels would make more than 1.8e19 faces",
            "the command line has no option",
        ],
    );
    assert!(!stderr(&out).contains("18446744073709551615"));
}

#[test]
fn levels_above_the_vertex_count_are_explained() {
    let dir = folder("levels");
    // Two solids sharing an edge: the repair copies vertices, so there are more levels than
    // vertices in the file.
    let stl = data("back_to_back_scad.stl");
    let said = ok(&meshpyr(&["build", &stl, "-o", &path(&dir, "b.pyr")]));
    assert!(
        said.contains("levels above 6 count the 7 vertex copies"),
        "{said}"
    );
    let info = meshpyr(&["info", &stl]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(text.contains("these 6 plus the 7 vertex copies"), "{text}");
    assert!(text.contains("1 vertex detached"), "{text}");
}

#[test]
fn compare_reports_zero_for_identical_files_and_explains_zero_e_v() {
    let bunny = data("bunny.ply");
    let same = meshpyr(&["compare", &bunny, &bunny, "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&same.stdout).unwrap();
    assert_eq!(
        (v["hausdorff"].as_f64(), v["e_v"].as_f64()),
        (Some(0.0), Some(0.0))
    );
    let dir = folder("compare");
    let coarse = path(&dir, "coarse.ply");
    ok(&meshpyr(&[
        "simplify", &bunny, "-o", &coarse, "--ratio", "0.1",
    ]));
    let text = meshpyr(&["compare", &coarse, &bunny]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("E_v is 0: every vertex of the result lies on"),
        "{text}"
    );
}
