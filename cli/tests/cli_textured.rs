//! Textured scans through the command line: what `info` says of them, what the commands that
//! keep faces write, the warnings of those that cannot keep everything, and `render` drawing
//! their texture.

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
    // The hierarchy keeps the seams, so its coarsest level is the seam floor (104 of the 519
    // vertices); a low-pass below it would act on the levels above only, with a warning.
    let run = meshpyr(&[
        "filter",
        &data(OBJ),
        "-o",
        out.to_str().unwrap(),
        "--lowpass",
        "300",
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
    let faces = textured_obj_faces(&text, &["mtllib ", "usemtl ", "\nvt ", "\nvn ", "\ng "]);
    assert!(faces < 600, "{faces} faces");
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

/// The `.pyr` of the textured OBJ built in `dir` with `--uv-weight 0.5` (not the default, so
/// that the file shows it records the weight), as a path argument.
fn built_with_uv_weight_half(dir: &str) -> String {
    let pyr = scratch_arg(dir, "scan.pyr");
    ok(&meshpyr(&[
        "build",
        &data(OBJ),
        "-o",
        &pyr,
        "--uv-weight",
        "0.5",
    ]));
    pyr
}

#[test]
fn extract_of_a_coarse_level_writes_its_texture_coordinates_materials_and_groups() {
    let pyr = built_with_uv_weight_half("cli_textured_levels");
    let out = scratch_arg("cli_textured_levels", "level.obj");
    let info = meshpyr::format::decode(&std::fs::read(&pyr).unwrap()).unwrap();
    assert_eq!(info.info.pm.uv_weight, 0.5, "the file records the weight");
    let (base, finest) = (info.pm.n_base_vertices(), info.pm.n_vertices());
    let level = (base + finest) / 2;
    let run = meshpyr(&["extract", &pyr, "-o", &out, "--level", &level.to_string()]);
    assert!(!ok(&run).contains("warning"), "{}", stderr(&run));
    let text = std::fs::read_to_string(&out).unwrap();
    let faces = textured_obj_faces(
        &text,
        &[
            "mtllib ",
            "usemtl left",
            "usemtl right",
            "\nvt ",
            "\nvn ",
            "\ng high",
        ],
    );
    assert_eq!(faces, info.pm.n_faces_at(level));
    // Below the seam floor there is no level, as below any file's base.
    fails_with(
        &meshpyr(&[
            "extract",
            &pyr,
            "-o",
            &out,
            "--level",
            &(base - 1).to_string(),
        ]),
        "outside this file's levels",
    );
}

#[test]
fn build_then_extract_gives_back_the_textured_obj() {
    let pyr = built_with_uv_weight_half("cli_textured_pyr");
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

/// The RGB pixels and width of a PNG picture.
fn picture(path: &str) -> (Vec<u8>, usize) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut rgb = vec![0; reader.output_buffer_size().unwrap()];
    let frame = reader.next_frame(&mut rgb).unwrap();
    assert_eq!(frame.color_type, png::ColorType::Rgb);
    (rgb, frame.width as usize)
}

/// Renders `input` front on at 160×160 into `out`, with `extra` options; returns the stderr.
fn render(input: &str, out: &str, extra: &[&str]) -> String {
    let mut args = vec!["render", input, "-o", out, "--size", "160x160"];
    args.extend_from_slice(extra);
    ok(&meshpyr(&args))
}

#[test]
fn render_draws_the_texture_where_it_varies_and_no_texture_draws_the_clay() {
    let textured = scratch_arg("cli_textured_render", "textured.png");
    let plain = scratch_arg("cli_textured_render", "plain.png");
    assert!(!render(&data(OBJ), &textured, &[]).contains("warning"));
    render(&data(OBJ), &plain, &["--no-texture"]);
    let ((a, _), (b, _)) = (picture(&textured), picture(&plain));
    let background = [255u8; 3];
    let surface: Vec<(&[u8], &[u8])> = a
        .chunks_exact(3)
        .zip(b.chunks_exact(3))
        .filter(|(_, q)| *q != background)
        .collect();
    assert!(surface.len() > 1000, "{} surface pixels", surface.len());
    // The clay is warm grey, red over green over blue; the texture's gradients and its two
    // images' blues (60 and 180) are not.
    assert!(surface.iter().all(|(_, q)| q[0] >= q[1] && q[1] >= q[2]));
    let coloured = surface
        .iter()
        .filter(|(p, _)| {
            let [r, g, b] = [p[0], p[1], p[2]].map(i32::from);
            g > r + 20 || b > r + 20
        })
        .count();
    assert!(
        coloured * 5 > surface.len(),
        "{coloured} of {} surface pixels show texture colours",
        surface.len()
    );
}

#[test]
fn the_ply_with_texture_files_renders_as_the_obj_with_its_library() {
    let (obj, ply) = (
        scratch_arg("cli_textured_render_ply", "obj.png"),
        scratch_arg("cli_textured_render_ply", "ply.png"),
    );
    render(&data(OBJ), &obj, &["--view", "iso"]);
    render(&data("textured/anchor_tex.ply"), &ply, &["--view", "iso"]);
    assert_eq!(picture(&obj), picture(&ply));
}

#[test]
fn a_checker_on_a_square_shows_its_colours_at_their_quarters() {
    let dir = scratch("cli_textured_checker", "square.obj");
    let obj = dir.display().to_string();
    std::fs::write(
        &dir,
        "mtllib square.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl checker\nf 1/1 2/2 3/3 4/4\n",
    )
    .unwrap();
    std::fs::write(
        dir.with_file_name("square.mtl"),
        "newmtl checker\nmap_Kd checker.png\n",
    )
    .unwrap();
    let mut rgb = Vec::new();
    for y in 0..8 {
        for x in 0..8 {
            rgb.extend_from_slice(match (x < 4, y < 4) {
                (true, true) => &[255u8, 0, 0],
                (false, true) => &[0, 255, 0],
                (true, false) => &[0, 0, 255],
                (false, false) => &[255, 255, 255],
            });
        }
    }
    let mut png_bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut png_bytes, 8, 8);
    encoder.set_color(png::ColorType::Rgb);
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(&rgb).unwrap();
    writer.finish().unwrap();
    std::fs::write(dir.with_file_name("checker.png"), &png_bytes).unwrap();
    let info = meshpyr(&["info", &obj]);
    let said = String::from_utf8_lossy(&info.stdout).into_owned();
    assert!(
        said.contains("texture coordinates: per vertex") && said.contains("checker.png: found"),
        "{said}"
    );
    let out = scratch_arg("cli_textured_checker", "square.png");
    render(&obj, &out, &[]);
    let (pixels, width) = picture(&out);
    let at = |x: usize, y: usize| {
        let i = 3 * (y * width + x);
        [pixels[i], pixels[i + 1], pixels[i + 2]]
    };
    // The square fills the panel but its margins; the light dims every channel alike.
    let lit = at(40, 40)[0];
    assert!(lit > 150, "{:?}", at(40, 40));
    assert_eq!(at(40, 40), [lit, 0, 0], "red top left (v = 1 at the top)");
    assert_eq!(at(120, 40), [0, lit, 0], "green top right");
    assert_eq!(at(40, 120), [0, 0, lit], "blue bottom left");
    assert_eq!(at(120, 120), [lit; 3], "white bottom right");

    std::fs::remove_file(dir.with_file_name("checker.png")).unwrap();
    let err = render(&obj, &out, &[]);
    assert!(
        err.contains("image checker.png") && err.contains("warning"),
        "{err}"
    );
    let info = meshpyr(&["info", &obj]);
    let said = String::from_utf8_lossy(&info.stdout).into_owned();
    assert!(said.contains("file checker.png: missing"), "{said}");
    let plain = scratch_arg("cli_textured_checker", "plain.png");
    render(&obj, &plain, &["--no-texture"]);
    assert_eq!(
        picture(&out),
        picture(&plain),
        "a missing image draws the clay"
    );
}

/// Checks that an OBJ text holds each of `markers` and that every corner of every face has
/// `v/vt/vn` indices; returns the number of faces.
fn textured_obj_faces(text: &str, markers: &[&str]) -> usize {
    for what in markers {
        assert!(text.contains(what), "{what:?} missing");
    }
    let faces: Vec<&str> = text.lines().filter(|l| l.starts_with("f ")).collect();
    assert!(
        faces
            .iter()
            .all(|f| f.split(' ').skip(1).all(|c| c.split('/').count() == 3)),
        "every corner has v/vt/vn"
    );
    faces.len()
}

/// A textured scan is built in blocks as any scan, forced or for a tight memory, and its
/// hierarchy keeps the seams: the coarse levels extract with their texture coordinates. Task
/// files do not carry the seams, so `--block-files` is refused for it.
#[test]
fn a_textured_scan_built_in_blocks_keeps_its_seams_and_block_files_are_refused() {
    let pyr = scratch_arg("cli_textured_blocks", "scan.pyr");
    let forced = meshpyr(&["build", &data(OBJ), "-o", &pyr, "--block-vertices", "128"]);
    let err = ok(&forced);
    assert!(
        err.contains("building the hierarchy in blocks of at most 128 vertices"),
        "{err}"
    );
    assert!(!err.contains("warning"), "{err}");
    let file = meshpyr::format::decode(&std::fs::read(&pyr).unwrap()).unwrap();
    assert!(file.pm.keeps_seams(), "the hierarchy keeps the seams");
    let level = scratch_arg("cli_textured_blocks", "level.obj");
    let base = file.pm.n_base_vertices();
    let at = (base + 40).to_string();
    let err = ok(&meshpyr(&["extract", &pyr, "-o", &level, "--level", &at]));
    assert!(!err.contains("warning"), "{err}");
    let text = std::fs::read_to_string(&level).unwrap();
    textured_obj_faces(&text, &["mtllib ", "usemtl ", "\nvt "]);
    let tight = scratch_arg("cli_textured_blocks", "tight.pyr");
    let err = ok(&meshpyr(&[
        "build",
        &data(OBJ),
        "-o",
        &tight,
        "--memory",
        "1K",
    ]));
    assert!(err.contains("building the hierarchy in blocks"), "{err}");
    let file = meshpyr::format::decode(&std::fs::read(&tight).unwrap()).unwrap();
    assert!(file.pm.keeps_seams(), "the hierarchy keeps the seams");
    let folder = scratch("cli_textured_blocks", "files");
    std::fs::create_dir_all(&folder).unwrap();
    let files = scratch_arg("cli_textured_blocks", "files.pyr");
    let refused = meshpyr(&[
        "build",
        &data(OBJ),
        "-o",
        &files,
        "--block-vertices",
        "128",
        "--block-files",
        folder.to_str().unwrap(),
    ]);
    fails_with(&refused, "do not carry its texture seams");
    assert!(stderr(&refused).contains("leave --block-files out"));
    assert!(!std::path::Path::new(&files).exists());
}

/// A low-pass below the seam floor acts on the levels above it: the warning says so, why the
/// levels stop there, and what asks for the same without the warning.
#[test]
fn a_low_pass_below_the_seam_floor_warns_naming_the_floor_and_what_to_ask_instead() {
    let out = scratch_arg("cli_textured_floor", "low.obj");
    let run = meshpyr(&["filter", &data(OBJ), "-o", &out, "--lowpass", "50"]);
    let err = ok(&run);
    let warning = err
        .lines()
        .find(|l| l.starts_with("warning: "))
        .unwrap_or_else(|| panic!("no warning in {err}"));
    let pyramid = meshpyr::Pyramid::build(&meshpyr::read_mesh(common::data(OBJ)).unwrap()).unwrap();
    let base = pyramid.levels().start().to_string();
    for needle in [
        "low-pass 50 reaches below the pyramid's coarsest level",
        "the seam floor",
        &format!("low-pass {base} does the same without this warning"),
    ] {
        assert!(warning.contains(needle), "{needle:?} not in {warning}");
    }
    let quiet = scratch_arg("cli_textured_floor", "quiet.obj");
    let run = meshpyr(&["filter", &data(OBJ), "-o", &quiet, "--lowpass", &base]);
    assert!(!ok(&run).contains("warning"), "{}", stderr(&run));
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&quiet).unwrap());
}
