//! Ohtake–Belyaev–Seidel denoising end to end: quality against the clean references, the
//! anisotropic variant on sharp features, determinism across thread counts, robustness on
//! dirty input, and the `meshpyr smooth` command.

use glam::DVec3;
use meshpyr::mesh::{Mesh, SlotIndex};
use meshpyr::metrics::{Reference, Surface};
use meshpyr::progress::NoProgress;
use meshpyr::smooth::{DenoiseOptions, Denoised, denoise};
use std::process::Command;

mod common;

use common::{data, on_threads};

/// The half-edge mesh of `name` (with its extension) in `tests/data`.
fn load(name: &str) -> Mesh {
    common::load(name.trim_end_matches(".ply"))
}

fn triangles(m: &Mesh) -> Vec<[u32; 3]> {
    m.faces()
        .map(|f| m.face_vertices(f).map(|v| v.slot() as u32))
        .collect()
}

/// E_n and E_v of `x` (positions by vertex slot, triangles `tris`) against the clean surface:
/// the library's exact metrics (`meshpyr compare`).
fn errors(clean: &[DVec3], x: &[DVec3], tris: &[[u32; 3]]) -> (f64, f64) {
    let reference = Reference::new(Surface::new(clean, tris)).expect("clean reference");
    let (e_v, e_n) = reference
        .errors(Surface::new(x, tris))
        .expect("result has area");
    (e_n, e_v)
}

struct Case {
    clean: Vec<DVec3>,
    noisy: Mesh,
    tris: Vec<[u32; 3]>,
}

fn case(noisy: &str, clean: &str) -> Case {
    let noisy = load(noisy);
    let c = load(clean);
    let tris = triangles(&noisy);
    assert_eq!(
        tris,
        triangles(&c),
        "noisy and clean meshes share connectivity"
    );
    Case {
        clean: c.positions(),
        noisy,
        tris,
    }
}

fn run(c: &Case, options: &DenoiseOptions) -> (Denoised, f64, f64) {
    let r = denoise(&c.noisy, options, &NoProgress).expect("denoising runs");
    assert!(r.positions.iter().all(|p| p.is_finite()));
    let (en, ev) = errors(&c.clean, &r.positions, &c.tris);
    (r, en, ev)
}

#[test]
fn fandisk_gets_closer_to_the_clean_part_and_anisotropic_keeps_the_edges() {
    for noisy in ["fandisk_noise_n020.ply", "fandisk_noise_i010.ply"] {
        let c = case(noisy, "fandisk.ply");
        let x0 = c.noisy.positions();
        let (en0, ev0) = errors(&c.clean, &x0, &c.tris);
        let (ra, en_a, ev_a) = run(&c, &DenoiseOptions::adaptive());
        let (_, en_b, ev_b) = run(&c, &DenoiseOptions::anisotropic());
        eprintln!(
            "{noisy}: noisy E_n {en0:.4} E_v {ev0:.3e}; adaptive {en_a:.4} {ev_a:.3e}; anisotropic {en_b:.4} {ev_b:.3e}"
        );
        assert!(ra.fit.final_energy < ra.fit.initial_energy);
        assert!(
            en_a < 0.6 * en0,
            "{noisy}: adaptive E_n {en_a} vs noisy {en0}"
        );
        assert!(
            ev_a < 0.8 * ev0,
            "{noisy}: adaptive E_v {ev_a} vs noisy {ev0}"
        );
        assert!(
            ev_b < 0.8 * ev0,
            "{noisy}: anisotropic E_v {ev_b} vs noisy {ev0}"
        );
        // Sharp edges survive only with the anisotropic neighbourhoods.
        assert!(
            en_b < 0.75 * en_a,
            "{noisy}: anisotropic E_n {en_b} vs adaptive {en_a}"
        );
    }
}

#[test]
fn noisy_bunny_gets_closer_to_the_clean_scan() {
    let c = case("bunny_noise_i010.ply", "bunny.ply");
    let x0 = c.noisy.positions();
    let (en0, ev0) = errors(&c.clean, &x0, &c.tris);
    let (_, en, ev) = run(&c, &DenoiseOptions::adaptive());
    eprintln!("bunny i010: noisy E_n {en0:.4} E_v {ev0:.3e}; adaptive {en:.4} {ev:.3e}");
    assert!(en < 0.4 * en0, "E_n {en} vs noisy {en0}");
    assert!(ev < 0.7 * ev0, "E_v {ev} vs noisy {ev0}");
}

#[test]
fn output_is_bitwise_identical_for_any_thread_count() {
    let mesh = load("cube_om_noisy.ply");
    for options in [DenoiseOptions::adaptive(), DenoiseOptions::anisotropic()] {
        let with = |threads: usize| {
            on_threads(threads, || {
                denoise(&mesh, &options, &NoProgress).expect("denoising runs")
            })
        };
        let one = with(1);
        let many = with(4);
        assert!(one.fit.iterations > 0);
        let bits = |d: &Denoised| -> Vec<[u64; 3]> {
            d.positions
                .iter()
                .map(|p| p.to_array().map(f64::to_bits))
                .collect()
        };
        assert_eq!(bits(&one), bits(&many));
        assert_eq!(one, many);
    }
}

#[test]
fn dirty_input_never_panics_or_produces_nan() {
    // A noisy open grid, a second component, a zero-area triangle, a triangle on an edge
    // shared by three (non-manifold, repaired by the builder) and an isolated vertex.
    let n = 10;
    let (mut p, mut t) = meshpyr::mesh::shapes::grid(n, |i, j| {
        let z = 0.05 * (((i * 7 + j * 13) % 11) as f64 / 11.0 - 0.5);
        DVec3::new(i as f64, j as f64, z)
    });
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let base = p.len() as u32;
    // Second component: a tetrahedron.
    p.extend([
        DVec3::new(20.0, 0.0, 0.0),
        DVec3::new(21.0, 0.0, 0.0),
        DVec3::new(20.0, 1.0, 0.0),
        DVec3::new(20.0, 0.0, 1.0),
    ]);
    t.extend([
        [base, base + 2, base + 1],
        [base, base + 1, base + 3],
        [base + 1, base + 2, base + 3],
        [base, base + 3, base + 2],
    ]);
    // Zero-area triangle: three collinear points.
    let z = p.len() as u32;
    p.extend([
        DVec3::new(30.0, 0.0, 0.0),
        DVec3::new(31.0, 0.0, 0.0),
        DVec3::new(32.0, 0.0, 0.0),
    ]);
    t.push([z, z + 1, z + 2]);
    // Two fins on the grid's boundary edge (0,0)-(1,0): that edge now has three triangles.
    let fin = p.len() as u32;
    p.push(DVec3::new(0.5, 0.0, -1.0));
    p.push(DVec3::new(0.5, -1.0, 0.3));
    t.push([id(0, 0), id(1, 0), fin]);
    t.push([id(1, 0), id(0, 0), fin + 1]);
    // Isolated vertex.
    let lonely = p.len();
    p.push(DVec3::new(-5.0, -5.0, -5.0));
    let built = Mesh::from_triangles(&p, &t).expect("buildable");
    assert!(built.report.non_manifold_edges > 0);
    for options in [DenoiseOptions::adaptive(), DenoiseOptions::anisotropic()] {
        let r = denoise(&built.mesh, &options, &NoProgress).expect("denoising runs");
        assert_eq!(r.positions.len(), built.mesh.n_vertices());
        assert!(r.positions.iter().all(|q| q.is_finite()));
        assert_eq!(r.positions[lonely], p[lonely]);
        // The collinear triangle's vertices have no defined normal anywhere: they stay.
        for v in z..z + 3 {
            assert_eq!(r.positions[v as usize], p[v as usize]);
        }
        assert!(r.fit.final_energy <= r.fit.initial_energy);
    }
    // Degenerate meshes: nothing at all, and only a zero-area face.
    let empty = Mesh::new();
    assert!(
        denoise(&empty, &DenoiseOptions::adaptive(), &NoProgress)
            .expect("empty mesh")
            .positions
            .is_empty()
    );
    let flat = Mesh::from_triangles(&[DVec3::ZERO; 3], &[[0, 1, 2]]).expect("buildable");
    let r = denoise(&flat.mesh, &DenoiseOptions::adaptive(), &NoProgress).expect("runs");
    assert_eq!(r.positions, vec![DVec3::ZERO; 3]);
}

#[test]
fn invalid_options_are_rejected() {
    let mesh = load("tetrahedron.ply");
    for bad in [
        DenoiseOptions {
            sigma_min: 0.0,
            ..DenoiseOptions::adaptive()
        },
        DenoiseOptions {
            sigma_min: 3.0,
            sigma_max: 2.0,
            ..DenoiseOptions::adaptive()
        },
        DenoiseOptions {
            scales: 0,
            ..DenoiseOptions::adaptive()
        },
        DenoiseOptions {
            epsilon: f64::NAN,
            ..DenoiseOptions::adaptive()
        },
        DenoiseOptions {
            rho: -1.0,
            ..DenoiseOptions::adaptive()
        },
        DenoiseOptions {
            step_cap: 0.0,
            ..DenoiseOptions::adaptive()
        },
        DenoiseOptions {
            reach: 0.0,
            ..DenoiseOptions::adaptive()
        },
        DenoiseOptions {
            reach: 4.5,
            ..DenoiseOptions::automatic()
        },
        DenoiseOptions {
            reach: f64::NAN,
            ..DenoiseOptions::adaptive()
        },
    ] {
        assert!(denoise(&mesh, &bad, &NoProgress).is_err(), "{bad:?}");
    }
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_meshpyr"))
}

fn tmp(name: &str) -> std::path::PathBuf {
    common::scratch("smooth", name)
}

#[test]
fn cli_keeps_vertices_order_and_faces() {
    let input = data("cube_om_noisy.ply");
    let before = meshpyr::io::read_mesh(&input).expect("readable");
    for method in ["adaptive", "anisotropic"] {
        let out = tmp(&format!("cube-{method}.ply"));
        let o = bin()
            .args(["smooth", "--quiet", "--method", method])
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(o.stderr.is_empty(), "--quiet prints nothing");
        let after = meshpyr::io::read_mesh(&out).expect("readable output");
        assert_eq!(after.n_vertices(), before.n_vertices());
        assert_eq!(after.n_faces(), before.n_faces());
        assert!(before.faces().eq(after.faces()), "faces unchanged");
        // Same order: every vertex moved by a fraction of the cube's size.
        let moved = before
            .positions
            .iter()
            .zip(&after.positions)
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max);
        assert!(moved > 0.0 && moved < 0.05, "{moved}");
    }
}

#[test]
fn cli_errors_are_one_line() {
    let out = tmp("never.ply");
    for args in [
        vec!["smooth", "/nonexistent/mesh.ply"],
        vec!["smooth", "--epsilon=-1"],
    ] {
        let mut cmd = bin();
        cmd.args(&args);
        if args.len() == 2 && args[1].starts_with("--") {
            cmd.arg(data("tetrahedron.ply"));
        }
        let o = cmd.arg("-o").arg(&out).output().expect("runs");
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.starts_with("error:"), "{err}");
    }
    assert!(!out.exists());
}

#[test]
fn filter_with_normal_relaxation_reproduces_and_filters_the_fandisk() {
    let input = data("fandisk.ply");
    let before = meshpyr::io::read_mesh(&input).expect("readable");
    let run = |extra: &[&str], name: &str| {
        let out = tmp(name);
        let o = bin()
            .args(["filter", "--quiet", "--relax", "normal"])
            .args(extra)
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        meshpyr::io::read_mesh(&out).expect("readable output")
    };
    let low = run(&["--lowpass", "1000"], "fandisk-low.ply");
    assert_eq!(low.n_vertices(), before.n_vertices());
    assert!(before.faces().eq(low.faces()));
    let moved = before
        .positions
        .iter()
        .zip(&low.positions)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    assert!(moved > 0.0, "the low-pass changes the shape");
    // Unit gains (a band with gain 1) give the input back.
    let same = run(&["--gain", "1000:2000=1"], "fandisk-unit.ply");
    let err = before
        .positions
        .iter()
        .zip(&same.positions)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    assert!(err < 1e-6, "{err}");
}

/// A scan far from the origin is denoised like the same scan at the origin. The noisy fandisk,
/// snapped to multiples of 2^-20, is translated by 2^20 exactly; the denoiser works relative to
/// the bounding-box centre, so both copies run the same arithmetic and the outputs differ only
/// by the rounding of the final translation back (a 2^20 coordinate's last bit, 2.3e-10). In
/// absolute coordinates the far copy's result moved by a quarter of the displacement.
#[test]
fn a_scan_far_from_the_origin_is_denoised_the_same() {
    let noisy = load("fandisk_noise_n020.ply");
    let offset = f64::from(1u32 << 20);
    let (near_mesh, far_mesh) = (
        common::snapped_and_moved(&noisy, 0.0),
        common::snapped_and_moved(&noisy, offset),
    );
    let start = near_mesh.positions();
    for options in [DenoiseOptions::adaptive(), DenoiseOptions::anisotropic()] {
        let near = denoise(&near_mesh, &options, &NoProgress).unwrap();
        let far = denoise(&far_mesh, &options, &NoProgress).unwrap();
        let (mut worst, mut moved_most) = (0.0f64, 0.0f64);
        for ((a, b), s) in near.positions.iter().zip(&far.positions).zip(&start) {
            worst = worst.max((*b - offset - *a).abs().max_element());
            moved_most = moved_most.max((*a - *s).length());
        }
        assert!(moved_most > 1e-3, "the denoiser moved nothing");
        assert!(worst <= 4.7e-10, "far copy differs by {worst:e}");
    }
}
