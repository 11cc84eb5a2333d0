//! Ohtake–Belyaev–Seidel denoising end to end: quality against the clean references, the
//! anisotropic variant on sharp features, determinism across thread counts, robustness on
//! dirty input, and the `meshpyr smooth` command.

use glam::DVec3;
use meshpyr::mesh::{Mesh, SlotIndex};
use meshpyr::progress::NoProgress;
use meshpyr::smooth::{DenoiseOptions, Denoised, denoise};
use std::path::{Path, PathBuf};
use std::process::Command;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn load(name: &str) -> Mesh {
    let input = meshpyr::io::read_mesh(&data(name)).expect("readable test mesh");
    Mesh::from_polygons(&input)
        .expect("buildable test mesh")
        .mesh
}

fn triangles(m: &Mesh) -> Vec<[u32; 3]> {
    m.faces()
        .map(|f| m.face_vertices(f).map(|v| v.slot() as u32))
        .collect()
}

fn area_vector(p: &[DVec3], t: [u32; 3]) -> DVec3 {
    (p[t[1] as usize] - p[t[0] as usize]).cross(p[t[2] as usize] - p[t[0] as usize])
}

/// E_n with the 1:1 face correspondence of a noisy copy: sqrt(Σ A' ‖n − n'‖² / Σ A').
fn normal_error(clean: &[DVec3], x: &[DVec3], tris: &[[u32; 3]]) -> f64 {
    let (mut sum, mut area) = (0.0, 0.0);
    for &t in tris {
        let a = area_vector(x, t);
        let w = 0.5 * a.length();
        sum += w
            * (area_vector(clean, t).normalize_or_zero() - a.normalize_or_zero()).length_squared();
        area += w;
    }
    (sum / area).sqrt()
}

/// Distance from `p` to triangle `abc` (closest point by barycentric clamping on edges).
fn point_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let n = (b - a).cross(c - a);
    if n.length_squared() > 0.0 {
        let q = p - n * (p - a).dot(n) / n.length_squared();
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| (v - u).cross(q - u).dot(n) >= 0.0);
        if inside {
            return (p - q).length();
        }
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|&(u, v)| {
            let e = v - u;
            let t = ((p - u).dot(e) / e.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            (p - (u + t * e)).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// E_v (area-weighted RMS distance of the vertices to the clean surface), with the closest
/// triangle searched in the two-ring of the corresponding clean vertex: the displacements are
/// a fraction of an edge, so the true closest triangle is there.
fn vertex_error(clean: &[DVec3], x: &[DVec3], tris: &[[u32; 3]]) -> f64 {
    let mut incident = vec![Vec::new(); clean.len()];
    for (f, t) in tris.iter().enumerate() {
        for &v in t {
            incident[v as usize].push(f);
        }
    }
    let mut vertex_area = vec![0.0; clean.len()];
    for &t in tris {
        let a = 0.5 * area_vector(x, t).length();
        for v in t {
            vertex_area[v as usize] += a;
        }
    }
    let (mut sum, mut total) = (0.0, 0.0);
    for v in 0..clean.len() {
        let mut best = f64::INFINITY;
        for &f in &incident[v] {
            for w in tris[f] {
                for &g in &incident[w as usize] {
                    let [a, b, c] = tris[g].map(|i| clean[i as usize]);
                    best = best.min(point_triangle(x[v], a, b, c));
                }
            }
        }
        if best.is_finite() {
            sum += vertex_area[v] * best * best;
            total += vertex_area[v];
        }
    }
    (sum / total).sqrt()
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
    let en = normal_error(&c.clean, &r.positions, &c.tris);
    let ev = vertex_error(&c.clean, &r.positions, &c.tris);
    (r, en, ev)
}

#[test]
fn fandisk_gets_closer_to_the_clean_part_and_anisotropic_keeps_the_edges() {
    for noisy in ["fandisk_noise_n020.ply", "fandisk_noise_i010.ply"] {
        let c = case(noisy, "fandisk.ply");
        let x0 = c.noisy.positions();
        let en0 = normal_error(&c.clean, &x0, &c.tris);
        let ev0 = vertex_error(&c.clean, &x0, &c.tris);
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
    let en0 = normal_error(&c.clean, &x0, &c.tris);
    let ev0 = vertex_error(&c.clean, &x0, &c.tris);
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
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool")
                .install(|| denoise(&mesh, &options, &NoProgress).expect("denoising runs"))
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
    let n = 10u32;
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let z = 0.05 * (((i * 7 + j * 13) % 11) as f64 / 11.0 - 0.5);
            p.push(DVec3::new(i as f64, j as f64, z));
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
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
    ] {
        assert!(denoise(&mesh, &bad, &NoProgress).is_err(), "{bad:?}");
    }
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_meshpyr"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("meshpyr-smooth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
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
