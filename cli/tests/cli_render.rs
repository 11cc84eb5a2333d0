//! `meshpyr render` end to end: picture sizes, options, one-line errors for bad input, and the
//! same bytes whatever the thread count (with `compare --per-vertex` making the field).

mod common;

use common::{data, error_line, meshpyr, ok, path};
use meshpyr::mesh::{Attribute, AttributeData};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn meshpyr_on_threads(args: &[&str], threads: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_meshpyr"));
    c.args(args);
    match threads {
        Some(n) => c.env("RAYON_NUM_THREADS", n),
        None => c.env_remove("RAYON_NUM_THREADS"),
    };
    c.output().unwrap()
}

fn png_size(file: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(file).unwrap()));
    let reader = decoder.read_info().unwrap();
    let info = reader.info();
    (info.width, info.height)
}

#[test]
fn one_input_gives_one_panel_of_the_asked_size() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("teapot.png");
    let teapot = data("teapot.ply");
    for extra in [
        &[][..],
        &["--view", "iso", "--smooth", "--wireframe"],
        &["--azimuth", "-30", "--elevation", "20"],
    ] {
        let mut args = vec!["render", path(&teapot), "-o", path(&out), "--size", "80x60"];
        args.extend_from_slice(extra);
        ok(&meshpyr(&args));
        assert_eq!(png_size(&out), (80, 60), "{extra:?}");
    }
}

#[test]
fn several_inputs_sit_side_by_side_with_captions() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ab.png");
    let (a, b) = (data("teapot.ply"), data("cone20.off"));
    ok(&meshpyr(&[
        "render",
        path(&a),
        path(&b),
        "-o",
        path(&out),
        "--size",
        "100x90",
    ]));
    let (w, h) = png_size(&out);
    // Two panels wide; the caption strip adds to the height.
    assert_eq!(w, 200);
    assert!(h > 90, "{h}");
    // A single input needs no caption.
    ok(&meshpyr(&[
        "render",
        path(&a),
        "-o",
        path(&out),
        "--size",
        "100x90",
    ]));
    assert_eq!(png_size(&out), (100, 90));
}

#[test]
fn views_and_options_change_the_picture() {
    let dir = tempfile::tempdir().unwrap();
    let teapot = data("teapot.ply");
    let draw = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["render", path(&teapot), "-o", path(&out), "--size", "64x64"];
        args.extend_from_slice(extra);
        ok(&meshpyr(&args));
        std::fs::read(out).unwrap()
    };
    let front = draw("front.png", &[]);
    assert_eq!(front, draw("front2.png", &["--view", "front"]));
    assert_eq!(front, draw("az0.png", &["--azimuth", "0"]));
    for (name, extra) in [
        ("top.png", &["--view", "top"][..]),
        ("smooth.png", &["--smooth"]),
        ("wire.png", &["--wireframe"]),
    ] {
        assert_ne!(front, draw(name, extra), "{name}");
    }
}

#[test]
fn unknown_attribute_is_named_with_the_available_ones() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let o = meshpyr(&[
        "render",
        path(&data("teapot.ply")),
        "-o",
        path(&out),
        "--color-by",
        "distanse",
    ]);
    let err = error_line(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("'distanse'") && err.contains("teapot.ply"),
        "{err}"
    );
    assert!(err.contains("available: none"), "{err}");
    assert!(!out.exists());

    // A mesh with attributes lists them.
    let mut mesh = meshpyr::read_mesh(data("cone20.ply")).unwrap();
    for name in ["quality", "distance"] {
        mesh.vertex_attributes.push(Attribute {
            name: name.into(),
            data: AttributeData::F32(vec![0.5; mesh.n_vertices()]),
        });
    }
    let file = dir.path().join("cone_attr.ply");
    meshpyr::write_mesh(&file, &mesh).unwrap();
    let teapot = data("teapot.ply");
    let both = |attribute: &str| {
        meshpyr(&[
            "render",
            path(&teapot),
            path(&file),
            "-o",
            path(&out),
            "--color-by",
            attribute,
        ])
    };
    let err = error_line(&both("height"));
    assert!(err.contains("teapot.ply, cone_attr.ply"), "{err}");
    assert!(err.contains("available: quality, distance"), "{err}");
    // One mesh with the attribute is enough; the other is drawn plain.
    ok(&both("quality"));
}

#[test]
fn bad_sizes_ranges_and_outputs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let teapot = data("teapot.ply");
    let run = |extra: &[&str], output: &Path| {
        let mut args = vec!["render", path(&teapot), "-o", path(output)];
        args.extend_from_slice(extra);
        error_line(&meshpyr(&args))
    };
    for size in ["0x96", "96", "96x99999", "ax5"] {
        let err = run(&["--size", size], &out);
        assert!(
            err.contains("--size") && err.contains("WxH"),
            "{size}: {err}"
        );
    }
    for range in ["1:0", "0:0", "0:inf", "a:b", "5"] {
        let err = run(&["--color-by", "distance", "--range", range], &out);
        assert!(
            err.contains("--range") && err.contains("MIN < MAX"),
            "{range}: {err}"
        );
    }
    // A range without anything to colour.
    assert!(run(&["--range", "0:1"], &out).contains("--color-by"));
    // A view and explicit angles at once.
    assert!(run(&["--view", "top", "--azimuth", "10"], &out).contains("--azimuth"));
    let err = run(&["--view", "sideways"], &out);
    assert!(err.contains("sideways") && err.contains("iso"), "{err}");
    let err = run(&[], &dir.path().join("x.jpg"));
    assert!(err.contains("x.jpg") && err.contains("png"), "{err}");
    let err = run(&["--level", "10"], &out);
    assert!(err.contains("--level") && err.contains(".pyr"), "{err}");
    assert!(!out.exists());
}

#[test]
fn pyr_levels_render_and_out_of_range_levels_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pyr = dir.path().join("teapot.pyr");
    ok(&meshpyr(&[
        "build",
        path(&data("teapot.ply")),
        "-o",
        path(&pyr),
        "--quiet",
    ]));
    let out = dir.path().join("level.png");
    let render = |level: &str| {
        meshpyr(&[
            "render",
            path(&pyr),
            "-o",
            path(&out),
            "--level",
            level,
            "--size",
            "64x64",
        ])
    };
    ok(&render("200"));
    let coarse = std::fs::read(&out).unwrap();
    ok(&render("700"));
    assert_ne!(coarse, std::fs::read(&out).unwrap());
    let err = error_line(&render("100000"));
    assert!(
        err.contains("--level 100000") && err.contains("outside"),
        "{err}"
    );
}

#[test]
fn field_and_picture_bytes_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (data("fandisk_noise_n020.ply"), data("fandisk.ply"));
    // The same file names in two folders: the captions are file names.
    let outputs = |threads: Option<&str>, tag: &str| -> (Vec<u8>, Vec<u8>) {
        let folder = dir.path().join(tag);
        std::fs::create_dir(&folder).unwrap();
        let field: PathBuf = folder.join("field.ply");
        let picture = folder.join("field.png");
        let compare = [
            "compare",
            path(&a),
            path(&b),
            "--per-vertex",
            path(&field),
            "--quiet",
        ];
        ok(&meshpyr_on_threads(&compare, threads));
        let render = [
            "render",
            path(&field),
            path(&b),
            "-o",
            path(&picture),
            "--size",
            "96x96",
            "--view",
            "iso",
            "--color-by",
            "distance",
        ];
        // The reference has no distance: drawn plain next to the coloured result.
        ok(&meshpyr_on_threads(&render, threads));
        (
            std::fs::read(field).unwrap(),
            std::fs::read(picture).unwrap(),
        )
    };
    let one = outputs(Some("1"), "one");
    let default = outputs(None, "default");
    assert!(
        one == default,
        "outputs differ between RAYON_NUM_THREADS=1 and the default"
    );
}
