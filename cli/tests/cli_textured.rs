//! Textured scans through the command line: what `info` says of them, what the commands that
//! keep faces write, and the warnings of those that cannot keep everything.

mod common;

use common::{data_arg as data, fails_with, meshpyr, ok, scratch, scratch_arg, stderr};

const OBJ: &str = "textured/anchor_tex.obj";

#[test]
fn info_reports_texture_coordinates_seams_materials_and_files() {
    let out = meshpyr(&["info", &data(OBJ)]);
    ok(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "per-corner texcoord: 1085 values on 3150 corners",
        "per-corner normal: 1054 values",
        "texture seams: 534 edges, 502 vertices",
        "materials: right left",
        "2 groups, 1 object",
        "file anchor_tex.mtl: found",
        "file textures/left.png: found",
    ] {
        assert!(text.contains(needle), "{needle:?} not in\n{text}");
    }
    let json = meshpyr(&["info", &data(OBJ), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(v["texture"]["seam_edges"], 534);
}

#[test]
fn filter_writes_vt_usemtl_and_a_library_path_that_reaches_the_same_file() {
    let out = scratch("cli_textured_filter", "deep/er/low.obj");
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    let run = meshpyr(&[
        "filter",
        &data(OBJ),
        "-o",
        out.to_str().unwrap(),
        "--lowpass",
        "60",
    ]);
    assert!(!ok(&run).contains("warning"), "{}", stderr(&run));
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("vt ")).count(), 1085);
    assert!(
        text.contains("usemtl left") && text.contains("g high") && text.contains("o anchor_tex")
    );
    let info = meshpyr(&["info", out.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&info.stdout).into_owned();
    assert!(said.contains("anchor_tex.mtl: found"), "{said}");
    assert!(!stderr(&info).contains("warning"), "{}", stderr(&info));
}

#[test]
fn a_missing_image_is_a_warning_and_the_output_is_still_written() {
    let obj = scratch("cli_textured_missing", "scan.obj");
    std::fs::write(
        &obj,
        "mtllib scan.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nvt 0 0\nusemtl skin\nf 1/1 2/1 3/1\nf 2/1 4/1 3/1\n",
    )
    .unwrap();
    std::fs::write(
        obj.with_file_name("scan.mtl"),
        "newmtl skin\nmap_Kd skin.png\n",
    )
    .unwrap();
    let out = scratch_arg("cli_textured_missing", "out.ply");
    let run = meshpyr(&["convert", obj.to_str().unwrap(), &out]);
    let err = ok(&run);
    assert!(
        err.contains("warning: ") && err.contains("image skin.png not found"),
        "{err}"
    );
}

#[test]
fn converting_to_off_says_what_is_not_carried_and_simplifying_carries_it() {
    let off = scratch_arg("cli_textured_off", "scan.off");
    let err = ok(&meshpyr(&["convert", &data(OBJ), &off]));
    assert!(
        err.contains("OFF cannot hold the mesh's per-corner texcoord"),
        "{err}"
    );
    let simplified = scratch_arg("cli_textured_off", "coarse.obj");
    let err = ok(&meshpyr(&[
        "simplify",
        &data(OBJ),
        "-o",
        &simplified,
        "--ratio",
        "0.5",
        "--uv-weight",
        "2",
    ]));
    assert!(!err.contains("does not carry"), "{err}");
    let text = std::fs::read_to_string(&simplified).unwrap();
    for what in ["mtllib ", "usemtl ", "\nvt ", "\nvn ", "\ng "] {
        assert!(text.contains(what), "{what:?} missing");
    }
    let faces: Vec<&str> = text.lines().filter(|l| l.starts_with("f ")).collect();
    assert!(faces.len() < 600, "{} faces", faces.len());
    assert!(
        faces
            .iter()
            .all(|f| f.split(' ').skip(1).all(|c| c.split('/').count() == 3)),
        "every corner has v/vt/vn"
    );
    fails_with(
        &meshpyr(&[
            "simplify",
            &data(OBJ),
            "-o",
            &simplified,
            "--ratio",
            "0.5",
            "--uv-weight=-1",
        ]),
        "uv weight must be finite and >= 0",
    );
}

#[test]
fn build_then_extract_gives_back_the_textured_obj() {
    let pyr = scratch_arg("cli_textured_pyr", "scan.pyr");
    ok(&meshpyr(&["build", &data(OBJ), "-o", &pyr]));
    let back = scratch_arg("cli_textured_pyr", "back.obj");
    ok(&meshpyr(&["extract", &pyr, "-o", &back]));
    let direct = scratch_arg("cli_textured_pyr", "direct.obj");
    ok(&meshpyr(&["convert", &data(OBJ), &direct]));
    assert_eq!(
        std::fs::read(&back).unwrap(),
        std::fs::read(&direct).unwrap(),
        "extract writes what convert writes"
    );
}
