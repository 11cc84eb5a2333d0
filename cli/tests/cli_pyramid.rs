//! `meshpyr filter`, `spectrum` and `edit` as a user runs them.

mod common;

use common::{data_arg as data, fails_with, meshpyr, ok, scratch};
use meshpyr::io;
use std::path::Path;

#[test]
fn filter_keeps_the_input_layout_and_changes_positions() {
    let input = data("elephant_holes.ply");
    let out = scratch("cli-pyramid", "elephant-low.ply");
    let o = meshpyr(&[
        "filter",
        &input,
        "-o",
        out.to_str().unwrap(),
        "--lowpass",
        "1400",
    ]);
    ok(&o);
    let a = io::read_mesh(Path::new(&input)).unwrap();
    let b = io::read_mesh(&out).unwrap();
    assert_eq!(a.positions.len(), b.positions.len());
    assert_eq!(a.face_starts, b.face_starts);
    assert_eq!(a.face_indices, b.face_indices);
    assert_ne!(a.positions, b.positions);

    // Several bands, sizes in model units, normal-only, all accepted; deterministic output.
    let out2 = scratch("cli-pyramid", "elephant-bands.ply");
    let out3 = scratch("cli-pyramid", "elephant-bands-again.ply");
    for o in [&out2, &out3] {
        ok(&meshpyr(&[
            "filter",
            &input,
            "-o",
            o.to_str().unwrap(),
            "--stopband",
            "500:1000",
            "--enhance",
            "0.05u:0.02u=1.5",
            "--gain",
            "2000:2800=0.5",
            "--normal-only",
            "--quiet",
        ]));
    }
    assert_eq!(std::fs::read(&out2).unwrap(), std::fs::read(&out3).unwrap());
}

#[test]
fn filter_with_the_mcm_relaxation_keeps_the_layout_and_differs_from_second_difference() {
    let input = data("elephant_holes.ply");
    let (mcm, sd) = (
        scratch("cli-pyramid", "elephant-mcm.ply"),
        scratch("cli-pyramid", "elephant-sd.ply"),
    );
    for (out, relax) in [(&mcm, "mcm"), (&sd, "second-difference")] {
        ok(&meshpyr(&[
            "filter",
            &input,
            "-o",
            out.to_str().unwrap(),
            "--lowpass",
            "1400",
            "--relax",
            relax,
            "--quiet",
        ]));
    }
    let a = io::read_mesh(Path::new(&input)).unwrap();
    let (m, s) = (io::read_mesh(&mcm).unwrap(), io::read_mesh(&sd).unwrap());
    assert_eq!(a.face_indices, m.face_indices);
    assert_eq!(a.positions.len(), m.positions.len());
    assert_ne!(a.positions, m.positions);
    assert_ne!(m.positions, s.positions);
}

#[test]
fn filter_rejects_missing_or_bad_filters() {
    let input = data("teapot.ply");
    let out = scratch("cli-pyramid", "never.ply");
    let o = out.to_str().unwrap();
    fails_with(&meshpyr(&["filter", &input, "-o", o]), "no filter given");
    let bad = meshpyr(&["filter", &input, "-o", o, "--enhance", "1000:2000"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("A:B=G"));
    fails_with(
        &meshpyr(&["filter", "/nonexistent/x.ply", "-o", o, "--lowpass", "10"]),
        "x.ply",
    );
    assert!(!out.exists());
}

/// A band that selects none of the pyramid's levels still filters (it changes nothing) but says
/// so, under `-q` too; bands that reach the levels say nothing.
#[test]
fn bands_outside_the_pyramid_are_reported() {
    let input = data("teapot.ply");
    let out = scratch("cli-pyramid", "teapot-band.ply");
    let o = out.to_str().unwrap();
    let run = |band: &[&str]| {
        let mut args = vec!["-q", "filter", &input, "-o", o];
        args.extend_from_slice(band);
        let r = meshpyr(&args);
        ok(&r);
        String::from_utf8_lossy(&r.stderr).into_owned()
    };
    let warned = |err: &str| err.contains("warning:") && err.contains("changes nothing");
    let err = run(&["--stopband", "50000:90000"]);
    assert!(warned(&err) && err.contains("band 50000:90000"), "{err}");
    assert!(warned(&run(&["--lowpass", "50000"])));
    assert!(warned(&run(&["--stopband", "300:300"])));
    // Finer than the scan's sampling: a feature size resolving far above the finest level.
    assert!(warned(&run(&["--enhance", "0.000001u:0.0000001u=2"])));
    // A unit gain changes nothing by design: no warning.
    assert_eq!(run(&["--gain", "50000:60000=1"]), "");
    assert_eq!(run(&["--stopband", "200:400", "--lowpass", "600"]), "");
    // Below the coarsest level (32 open patches: at least 96 vertices): the low-pass keeps
    // the base level, not 10 vertices, and says so.
    let err = run(&["--lowpass", "10"]);
    assert!(
        err.contains("warning:")
            && err.contains("low-pass 10 reaches below the pyramid's coarsest level"),
        "{err}"
    );
    assert!(out.exists());
}

#[test]
fn spectrum_writes_a_png_and_a_csv() {
    let png = scratch("cli-pyramid", "spider.png");
    let csv = scratch("cli-pyramid", "spider.csv");
    ok(&meshpyr(&[
        "spectrum",
        &data("spider_assimp.ply"),
        "-o",
        png.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let table = std::fs::read_to_string(&csv).unwrap();
    let mut lines = table.lines();
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("level_from,level_to,levels,details,energy")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() >= 3);
    // Octaves tile the levels: each starts where the previous ended.
    for w in rows.windows(2) {
        assert_eq!(w[0][1], w[1][0]);
    }
    assert!(rows.iter().all(|r| r[4] >= 0.0 && r[4].is_finite()));
}

#[test]
fn edit_moves_the_surface_near_the_handle_only() {
    let input = data("elephant_holes.ply");
    let a = io::read_mesh(Path::new(&input)).unwrap();
    // Grab the vertex with the largest y and lift it.
    let top = a
        .positions
        .iter()
        .copied()
        .max_by(|p, q| p.y.total_cmp(&q.y))
        .unwrap();
    let out = scratch("cli-pyramid", "elephant-edit.ply");
    let handle = format!("{},{},{}:0,0.1,0", top.x, top.y, top.z);
    ok(&meshpyr(&[
        "edit",
        &input,
        "-o",
        out.to_str().unwrap(),
        "--level",
        "400",
        "--move",
        &handle,
        "--radius",
        "0.3",
    ]));
    let b = io::read_mesh(&out).unwrap();
    assert_eq!(a.face_indices, b.face_indices);
    let moved = |i: usize| (b.positions[i] - a.positions[i]).length();
    let near = (0..a.positions.len())
        .filter(|&i| (a.positions[i] - top).length() < 0.05)
        .map(moved)
        .fold(0.0, f64::max);
    let far = (0..a.positions.len())
        .filter(|&i| (a.positions[i] - top).length() > 0.9)
        .map(moved)
        .fold(0.0, f64::max);
    assert!(near > 0.03, "{near}");
    assert!(far < 0.005, "{far}");

    let o = out.to_str().unwrap();
    fails_with(
        &meshpyr(&[
            "edit", &input, "-o", o, "--level", "1", "--move", &handle, "--radius", "1",
        ]),
        "outside this mesh's levels",
    );
    fails_with(
        &meshpyr(&[
            "edit",
            &input,
            "-o",
            o,
            "--level",
            "400",
            "--move",
            &handle,
            "--radius=-1",
        ]),
        "--radius",
    );
    let bad = meshpyr(&[
        "edit", &input, "-o", o, "--level", "400", "--move", "1,2:3", "--radius", "1",
    ]);
    assert!(!bad.status.success());
}

#[test]
fn demo_writes_filtered_versions_spectrum_and_previews() {
    let dir = scratch("cli-pyramid", "demo");
    let out = meshpyr(&["demo", "--out", dir.to_str().unwrap()]);
    ok(&out);
    let log = String::from_utf8_lossy(&out.stderr);
    for name in [
        "bunny-lowpass.ply",
        "bunny-stopband.ply",
        "bunny-enhanced.ply",
        "bunny-spectrum.png",
        "bunny-spectrum.csv",
        "bunny-preview.png",
        "bunny-input.png",
        "bunny-enhanced.png",
    ] {
        let path = dir.join(name);
        assert!(path.exists(), "{name} missing");
        assert!(log.contains(name), "the demo says where {name} went: {log}");
    }
    let input = io::read_mesh(Path::new(&data("bunny.ply"))).unwrap();
    let low = io::read_mesh(dir.join("bunny-lowpass.ply")).unwrap();
    assert_eq!(input.face_indices, low.face_indices);
    assert_ne!(input.positions, low.positions);
    let csv = std::fs::read_to_string(dir.join("bunny-spectrum.csv")).unwrap();
    for series in ["input,", "lowpass,", "stopband,", "enhanced,"] {
        assert!(csv.lines().any(|l| l.starts_with(series)), "{series}");
    }
}

/// Scan coordinates are often negative: `--move` takes them as written, without `--move=`.
#[test]
fn edit_accepts_negative_coordinates_in_a_move() {
    let input = data("teapot.ply");
    let out = scratch("cli-pyramid", "teapot-negative-move.ply");
    let o = out.to_str().unwrap();
    ok(&meshpyr(&[
        "-q",
        "edit",
        &input,
        "-o",
        o,
        "--level",
        "200",
        "--move",
        "-0.5,-0.5,-0.5:0,-0.1,0",
        "--radius",
        "1",
    ]));
    let (a, b) = (io::read_mesh(&input).unwrap(), io::read_mesh(&out).unwrap());
    assert_eq!(a.face_indices, b.face_indices);
    assert_ne!(a.positions, b.positions);
}

/// `--lowpass` needs a level of at least one vertex; zero and negative numbers get an error
/// that says why, not clap's advice to write `-- -1`.
#[test]
fn lowpass_rejects_zero_and_negative_levels() {
    let input = data("teapot.ply");
    let out = scratch("cli-pyramid", "never-lowpass.ply");
    let o = out.to_str().unwrap();
    for (level, why) in [("0", "must be at least 1"), ("-1", "not a negative number")] {
        let r = meshpyr(&["filter", &input, "-o", o, "--lowpass", level]);
        assert!(!r.status.success());
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.starts_with("error: ") && err.contains(why), "{err}");
        assert!(!err.contains("-- -1"), "{err}");
    }
    assert!(!out.exists());
}
