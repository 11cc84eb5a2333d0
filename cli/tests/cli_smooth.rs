//! `meshpyr smooth` end to end: layout kept, methods improve a noisy fandisk, determinism,
//! error exits.

mod common;

use common::data;
use meshpyr::mesh::{Attribute, AttributeData, PolygonMesh};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_meshpyr"))
}

fn tmp(name: &str) -> PathBuf {
    common::scratch("cli-smooth", name)
}

fn smooth(input: &Path, output: &Path, extra: &[&str]) -> Output {
    bin()
        .arg("smooth")
        .arg(input)
        .arg("-o")
        .arg(output)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap()
}

fn e_n(result: &Path, reference: &Path) -> f64 {
    let a = meshpyr::mesh::Mesh::from_polygons(&meshpyr::io::read_mesh(result).unwrap())
        .unwrap()
        .mesh;
    let b = meshpyr::mesh::Mesh::from_polygons(&meshpyr::io::read_mesh(reference).unwrap())
        .unwrap()
        .mesh;
    meshpyr::metrics::compare(&a, &b).unwrap().e_n
}

#[test]
fn every_method_improves_the_noisy_fandisk_and_keeps_the_layout() {
    let noisy = data("fandisk_noise_n020.ply");
    let clean = data("fandisk.ply");
    let before = e_n(&noisy, &clean);
    let input = meshpyr::io::read_mesh(&noisy).unwrap();
    for extra in [
        vec![],
        vec![
            "--method",
            "taubin",
            "--weights",
            "uniform",
            "--iterations",
            "5",
        ],
        vec![
            "--method",
            "taubin",
            "--weights",
            "inverse-edge",
            "--lambda",
            "0.6",
            "--mu",
            "-0.64",
        ],
        vec!["--method", "mcf"],
        vec!["--method", "mcf", "--iterations", "2", "--time-step", "0.5"],
        vec!["--method", "taubin", "--boundary", "smooth"],
    ] {
        let out = tmp("fandisk.ply");
        let o = smooth(&noisy, &out, &extra);
        assert!(
            o.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(o.stderr.is_empty(), "--quiet prints nothing");
        let result = meshpyr::io::read_mesh(&out).unwrap();
        assert_eq!(result.n_vertices(), input.n_vertices());
        assert_eq!(result.face_starts, input.face_starts);
        assert_eq!(result.face_indices, input.face_indices);
        assert_ne!(result.positions, input.positions);
        let after = e_n(&out, &clean);
        assert!(after < 0.8 * before, "{extra:?}: E_n {before} -> {after}");
    }
}

#[test]
fn attributes_unreferenced_vertices_and_polygons_survive() {
    // A noisy 4x4 quad grid with a per-vertex scalar and one vertex no face uses.
    let n = 4;
    let mut m = PolygonMesh::new();
    for j in 0..=n {
        for i in 0..=n {
            let z = if (i + j) % 2 == 0 { 0.05 } else { -0.05 };
            m.positions.push(glam::DVec3::new(i as f64, j as f64, z));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
            m.push_face(&[id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    m.positions.push(glam::DVec3::new(9.0, 9.0, 9.0));
    let nv = m.positions.len();
    m.vertex_attributes.push(Attribute {
        name: "quality".into(),
        data: AttributeData::F32((0..nv).map(|i| i as f32).collect()),
    });
    let input = tmp("quads.ply");
    meshpyr::io::write_mesh(&input, &m).unwrap();
    for method in ["taubin", "mcf"] {
        let out = tmp(&format!("quads_{method}.ply"));
        let o = smooth(&input, &out, &["--method", method]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r = meshpyr::io::read_mesh(&out).unwrap();
        assert_eq!(r.face_starts, m.face_starts);
        assert_eq!(r.face_indices, m.face_indices);
        assert_eq!(r.vertex_attributes, m.vertex_attributes);
        assert_eq!(
            r.positions[nv - 1],
            m.positions[nv - 1],
            "unreferenced vertex"
        );
        // The rim is fixed by default; the interior got flatter.
        assert_eq!(r.positions[0], m.positions[0]);
        let bump = |p: &[glam::DVec3]| p[6].z.abs() + p[12].z.abs() + p[18].z.abs();
        assert!(bump(&r.positions) < 0.5 * bump(&m.positions), "{method}");
    }
}

#[test]
fn output_is_byte_identical_across_runs_and_thread_counts() {
    for method in ["taubin", "mcf"] {
        let run = |name: &str, threads: &str| {
            let out = tmp(name);
            let ok = bin()
                .env("RAYON_NUM_THREADS", threads)
                .args(["smooth", "-q", "--method", method])
                .arg(data("fandisk_noise_i010.ply"))
                .arg("-o")
                .arg(&out)
                .status()
                .unwrap()
                .success();
            assert!(ok);
            std::fs::read(out).unwrap()
        };
        let a = run(&format!("{method}_a.ply"), "1");
        assert_eq!(a, run(&format!("{method}_b.ply"), "2"));
        assert_eq!(a, run(&format!("{method}_c.ply"), "3"));
    }
}

#[test]
fn bad_input_exits_nonzero_with_one_line() {
    for args in [
        vec!["--method", "taubin", "--lambda", "0"],
        vec!["--method", "taubin", "--lambda", "2"],
        vec!["--method", "taubin", "--mu", "0.3"],
        vec!["--method", "mcf", "--time-step", "-1"],
        vec!["--method", "mcf", "--time-step", "nan"],
        vec!["--reach", "0"],
        vec!["--method", "adaptive", "--reach", "4.5"],
    ] {
        let o = smooth(&data("cone20.ply"), &tmp("never.ply"), &args);
        assert!(!o.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.starts_with("error: "), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
    assert!(!tmp("never.ply").exists());
    let o = smooth(Path::new("/nonexistent/x.ply"), &tmp("x.ply"), &[]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: "));
}

#[test]
fn an_option_of_another_method_is_refused_before_any_work() {
    for (args, option, method) in [
        (
            vec!["--method", "taubin", "--epsilon", "3"],
            "--epsilon",
            "taubin",
        ),
        (vec!["--rho", "2", "--method", "mcf"], "--rho", "mcf"),
        (vec!["--lambda", "0.4"], "--lambda", "auto"),
        (
            vec!["--method", "mcf", "--weights", "uniform"],
            "--weights",
            "mcf",
        ),
        (
            vec!["--method", "anisotropic", "--iterations", "3"],
            "--iterations",
            "anisotropic",
        ),
        (
            vec!["--method", "taubin", "--time-step", "2"],
            "--time-step",
            "taubin",
        ),
        (vec!["--strength", "2"], "--strength", "auto"),
        (
            vec!["--method", "taubin", "--reach", "3"],
            "--reach",
            "taubin",
        ),
        (
            vec!["--method", "pyramid", "--passes", "2"],
            "--passes",
            "pyramid",
        ),
    ] {
        let out = tmp("refused.ply");
        let o = smooth(&data("cone20.ply"), &out, &args);
        assert!(!o.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(&format!(
                "{} does not apply to method {method}",
                option.trim_start_matches("--").replace('-', "_")
            )),
            "{err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!out.exists());
    }
}

#[test]
fn options_of_the_chosen_method_are_accepted() {
    for args in [
        vec![
            "--method",
            "taubin",
            "--iterations",
            "3",
            "--boundary",
            "smooth",
        ],
        vec!["--method", "mcf", "--iterations", "2", "--time-step", "0.5"],
        vec!["--method", "anisotropic", "--epsilon", "0.5", "--rho", "3"],
        vec!["--method", "pyramid", "--strength", "0.5"],
        vec!["--method", "adaptive", "--reach", "3"],
        vec![
            "--passes",
            "1",
            "--vertex-updates",
            "3",
            "--scale",
            "global",
        ],
    ] {
        let o = smooth(&data("cone20.ply"), &tmp("accepted.ply"), &args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

#[test]
fn default_smooth_denoises_a_non_uniformly_sampled_scan_at_each_triangles_scale() {
    // Edge lengths vary about eightfold; the noise is 0.2 of the *mean* edge along the
    // normals, so small triangles carry noise as large as themselves.
    let noisy = data("lion_head_noise_n020.ply");
    let clean = data("lion_head.ply");
    let before = e_n(&noisy, &clean);
    let (auto, adaptive) = (tmp("lion-auto.ply"), tmp("lion-adaptive.ply"));
    assert!(smooth(&noisy, &auto, &[]).status.success());
    let o = smooth(&noisy, &adaptive, &["--method", "adaptive"]);
    assert!(o.status.success());
    let (e_auto, e_adaptive) = (e_n(&auto, &clean), e_n(&adaptive, &clean));
    assert!(e_auto < 0.35 * before, "{e_auto} from {before}");
    // The paper's one pass in units of the mean edge barely helps here.
    assert!(
        e_auto < 0.5 * e_adaptive,
        "{e_auto} vs adaptive {e_adaptive}"
    );
}

#[test]
fn the_pyramid_method_keeps_the_fandisks_creases_better_than_the_default() {
    let noisy = data("fandisk_noise_n020.ply");
    let clean = data("fandisk.ply");
    let (auto, pyramid) = (tmp("fandisk-auto.ply"), tmp("fandisk-pyramid.ply"));
    assert!(smooth(&noisy, &auto, &[]).status.success());
    let o = smooth(&noisy, &pyramid, &["--method", "pyramid"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (e_auto, e_pyramid) = (e_n(&auto, &clean), e_n(&pyramid, &clean));
    assert!(
        e_pyramid < 0.75 * e_auto,
        "pyramid {e_pyramid} vs default {e_auto}"
    );
    let layout = |p: &Path| {
        let m = meshpyr::io::read_mesh(p).unwrap();
        (m.n_vertices(), m.face_indices)
    };
    assert_eq!(layout(&pyramid), layout(&noisy));
    // More strength removes more of the finest details; zero removes nothing.
    let none = tmp("fandisk-pyramid-0.ply");
    assert!(
        smooth(&noisy, &none, &["--method", "pyramid", "--strength", "0"])
            .status
            .success()
    );
    let unchanged = e_n(&none, &clean);
    assert!(
        (unchanged - e_n(&noisy, &clean)).abs() < 1e-6,
        "{unchanged}"
    );
}
