//! Denoising sweep in the form of Ohtake–Belyaev–Seidel 2002, Fig. 10: for each noisy mesh, the
//! baselines over their iteration counts, reporting the best E_n (with the count and the E_v
//! there) and the best E_v.
//!
//! ```sh
//! cargo test --release --test denoise_report -- --ignored --nocapture
//! ```
//!
//! To add a method, add one line to `methods()`: a name, the counts to evaluate, and a step
//! function that advances the mesh by one iteration (a one-pass method uses `&[1]`).
//!
//! The non-ignored test at the bottom is a fast regression check with tuned parameters.

use glam::DVec3;
use meshpyr::mesh::Mesh;
use meshpyr::metrics::{Reference, Surface};
use meshpyr::progress::NoProgress;
use meshpyr::smooth::{
    Boundary, DenoiseOptions, McfOptions, TaubinOptions, Weights, implicit_mcf, taubin_smoothing,
};
use std::path::Path;

fn load(name: &str) -> Mesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    Mesh::from_polygons(&meshpyr::io::read_mesh(&path).unwrap())
        .unwrap()
        .mesh
}

/// What a step sees besides the mesh: the input's mean edge length (MCF time steps refer to it,
/// not to the shrinking surface's).
struct Context {
    input_edge: f64,
}

type Step = Box<dyn Fn(&Mesh, &Context) -> Result<Vec<DVec3>, String>>;

struct Method {
    name: String,
    /// Iteration counts at which the errors are measured (increasing).
    counts: Vec<usize>,
    step: Step,
}

const TAUBIN_COUNTS: &[usize] = &[
    1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 60, 80, 100, 130, 160, 200,
];
const MCF_COUNTS: &[usize] = &[1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20];

fn taubin(weights: Weights) -> Step {
    Box::new(move |m: &Mesh, _: &Context| {
        let o = TaubinOptions {
            iterations: 1,
            weights,
            ..Default::default()
        };
        taubin_smoothing(m, &o, &NoProgress).map_err(|e| e.to_string())
    })
}

fn denoise(options: DenoiseOptions) -> Step {
    Box::new(move |m: &Mesh, _: &Context| {
        meshpyr::smooth::denoise(m, &options, &NoProgress)
            .map(|d| d.positions)
            .map_err(|e| e.to_string())
    })
}

fn mcf(time_step: f64) -> Step {
    Box::new(move |m: &Mesh, c: &Context| {
        let l = m.mean_edge_length();
        let o = McfOptions {
            iterations: 1,
            time_step: time_step * (c.input_edge / l).powi(2),
            boundary: Boundary::Fixed,
        };
        implicit_mcf(m, &o, &NoProgress).map_err(|e| e.to_string())
    })
}

fn methods() -> Vec<Method> {
    let m = |name: &str, counts: &[usize], step: Step| Method {
        name: name.to_string(),
        counts: counts.to_vec(),
        step,
    };
    vec![
        m(
            "Taubin λ|μ, equal weights",
            TAUBIN_COUNTS,
            taubin(Weights::Uniform),
        ),
        m(
            "Taubin λ|μ, inverse edge length",
            TAUBIN_COUNTS,
            taubin(Weights::InverseEdgeLength),
        ),
        m(
            "Taubin λ|μ, cotangent",
            TAUBIN_COUNTS,
            taubin(Weights::Cotangent),
        ),
        m("implicit MCF, dt = 0.1 L²", MCF_COUNTS, mcf(0.1)),
        m("implicit MCF, dt = 0.25 L²", MCF_COUNTS, mcf(0.25)),
        m("implicit MCF, dt = 1 L²", MCF_COUNTS, mcf(1.0)),
        m("implicit MCF, dt = 4 L²", MCF_COUNTS, mcf(4.0)),
        // The paper's method: one default pass, no per-mesh tuning.
        m(
            "adaptive, one default pass",
            &[1],
            denoise(DenoiseOptions::adaptive()),
        ),
        m(
            "anisotropic, one default pass",
            &[1],
            denoise(DenoiseOptions::anisotropic()),
        ),
    ]
}

struct Best {
    e_n: (f64, usize, f64),
    e_v: (f64, usize),
    /// The iteration at which the method failed, and why (the sweep stops there).
    failed: Option<(usize, String)>,
}

fn errors(reference: &Reference, mesh: &Mesh) -> (f64, f64) {
    let (p, t) = mesh.to_triangles();
    reference.errors(Surface::new(&p, &t)).unwrap()
}

fn sweep(reference: &Reference, noisy: &Mesh, method: &Method) -> Best {
    let ctx = Context {
        input_edge: noisy.mean_edge_length(),
    };
    let mut mesh = noisy.clone();
    let mut done = 0;
    let mut best = Best {
        e_n: (f64::INFINITY, 0, 0.0),
        e_v: (f64::INFINITY, 0),
        failed: None,
    };
    for &count in &method.counts {
        while done < count {
            let x = match (method.step)(&mesh, &ctx) {
                Ok(x) => x,
                Err(e) => {
                    best.failed = Some((done + 1, e));
                    return best;
                }
            };
            let ids: Vec<_> = mesh.vertices().collect();
            for (v, p) in ids.into_iter().zip(x) {
                mesh.set_position(v, p);
            }
            done += 1;
        }
        let (e_v, e_n) = errors(reference, &mesh);
        if e_n < best.e_n.0 {
            best.e_n = (e_n, count, e_v);
        }
        if e_v < best.e_v.0 {
            best.e_v = (e_v, count);
        }
    }
    best
}

#[test]
#[ignore = "slow sweep; run with --release -- --ignored --nocapture"]
fn denoise_sweep_table() {
    let cases = [
        ("bunny_noise_n020.ply", "bunny.ply"),
        ("bunny_noise_i010.ply", "bunny.ply"),
        ("fandisk_noise_n020.ply", "fandisk.ply"),
        ("fandisk_noise_i010.ply", "fandisk.ply"),
        ("cube_om_noisy.ply", "cube_om.ply"),
    ];
    let methods = methods();
    for (noisy_name, clean_name) in cases {
        let reference = Reference::from_mesh(&load(clean_name)).unwrap();
        let noisy = load(noisy_name);
        let l = reference.mean_edge_length();
        let (e_v0, e_n0) = errors(&reference, &noisy);
        println!("\n**{noisy_name}** against {clean_name} (L = {l:.5}; E_v also as E_v/L)\n");
        println!("| method | best E_n (iterations) | E_v at that count | best E_v (iterations) |");
        println!("|---|---|---|---|");
        println!(
            "| noisy input | {e_n0:.4} | {e_v0:.3e} ({:.3} L) | {e_v0:.3e} ({:.3} L) |",
            e_v0 / l,
            e_v0 / l
        );
        for method in &methods {
            let b = sweep(&reference, &noisy, method);
            let note = b.failed.map_or(String::new(), |(i, e)| {
                eprintln!("{}: stopped at iteration {i}: {e}", method.name);
                format!(" (solver failed at iteration {i})")
            });
            println!(
                "| {}{} | {:.4} ({}) | {:.3e} ({:.3} L) | {:.3e} ({:.3} L) ({}) |",
                method.name,
                note,
                b.e_n.0,
                b.e_n.1,
                b.e_n.2,
                b.e_n.2 / l,
                b.e_v.0,
                b.e_v.0 / l,
                b.e_v.1
            );
        }
    }
}

/// Fast regression check: with parameters tuned by the sweep above, both baselines must
/// roughly halve the normal error of the noisy fandisk, and lower its vertex error.
#[test]
fn tuned_baselines_improve_the_noisy_fandisk() {
    let reference = Reference::from_mesh(&load("fandisk.ply")).unwrap();
    let noisy = load("fandisk_noise_n020.ply");
    let (e_v0, e_n0) = errors(&reference, &noisy);
    let with = |x: Vec<DVec3>| {
        let mut m = noisy.clone();
        let ids: Vec<_> = m.vertices().collect();
        for (v, p) in ids.into_iter().zip(x) {
            m.set_position(v, p);
        }
        errors(&reference, &m)
    };
    let taubin = TaubinOptions {
        iterations: 6,
        weights: Weights::Uniform,
        ..Default::default()
    };
    let mcf = McfOptions {
        iterations: 2,
        time_step: 0.25,
        boundary: Boundary::Fixed,
    };
    for (name, (e_v, e_n)) in [
        (
            "taubin",
            with(taubin_smoothing(&noisy, &taubin, &NoProgress).unwrap()),
        ),
        (
            "mcf",
            with(implicit_mcf(&noisy, &mcf, &NoProgress).unwrap()),
        ),
    ] {
        assert!(e_n < 0.55 * e_n0, "{name}: E_n {e_n0} -> {e_n}");
        assert!(e_v < 0.8 * e_v0, "{name}: E_v {e_v0} -> {e_v}");
    }
}
