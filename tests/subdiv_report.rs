//! Prints the quality tables of the README's Subdivision section (run manually:
//! `cargo test --release --test subdiv_report -- --ignored --nocapture`).

mod common;

use common::*;
use meshpyr::mesh::{Mesh, SlotIndex};
use meshpyr::metrics::curvature::{curvature_stats, gauss_curvature, ring_sign_changes};
use meshpyr::progress::NoProgress;
use meshpyr::subdiv::{Scheme, Solver, SubdivOptions, subdivide};

fn run(mesh: &Mesh, opts: SubdivOptions) -> Mesh {
    subdivide(mesh, &opts, &NoProgress).unwrap().mesh().unwrap()
}

#[test]
#[ignore]
fn quality_table() {
    let levels = 3;
    println!(
        "levels = {levels}; rings = {} around interior vertices of valence >= 8",
        1 << (levels - 1)
    );
    println!(
        "| mesh (max valence, #EV>=8) | scheme | var H·R | roughness | sign changes (hybrid rings / rings) | volume / input | max |x − x_exact| / diag |"
    );
    println!("|---|---|---|---|---|---|---|");
    for name in CONTROL_MESHES {
        let coarse = load(name);
        let maxval = coarse.vertices().map(|v| coarse.valence(v)).max().unwrap();
        let evs: Vec<_> = coarse
            .vertices()
            .filter(|&v| !coarse.is_boundary_vertex(v) && coarse.valence(v) >= 8)
            .collect();
        let v0 = volume(&coarse);
        let diag = coarse.bbox_diagonal();
        let exact = run(
            &coarse,
            SubdivOptions {
                solver: Solver::Exact,
                levels,
                ..Default::default()
            },
        );
        for (label, opts) in [
            (
                "Loop",
                SubdivOptions {
                    scheme: Scheme::Loop,
                    levels,
                    ..Default::default()
                },
            ),
            (
                "MCM exact",
                SubdivOptions {
                    solver: Solver::Exact,
                    levels,
                    ..Default::default()
                },
            ),
            (
                "MCM cg (default)",
                SubdivOptions {
                    levels,
                    ..Default::default()
                },
            ),
            (
                "MCM jacobi",
                SubdivOptions {
                    solver: Solver::Jacobi,
                    levels,
                    ..Default::default()
                },
            ),
            (
                "MCM exact, local width",
                SubdivOptions {
                    solver: Solver::Exact,
                    local_width: true,
                    levels,
                    ..Default::default()
                },
            ),
        ] {
            let m = run(&coarse, opts.clone());
            let s = curvature_stats(&m);
            let k = gauss_curvature(&m);
            let ids: Vec<_> = m.vertices().collect();
            let centres: Vec<_> = evs.iter().map(|v| ids[v.slot()]).collect();
            let r = ring_sign_changes(&m, &k, &centres, 1 << (levels - 1), 1e-2);
            let diff = if opts.scheme == Scheme::Mcm && opts.solver != Solver::Exact {
                let d = m
                    .positions()
                    .iter()
                    .zip(exact.positions())
                    .map(|(a, b)| (*a - b).length())
                    .fold(0.0, f64::max);
                format!("{:.4}", d / diag)
            } else {
                "–".to_string()
            };
            println!(
                "| {name} ({maxval}, {}) | {label} | {:.3} | {:.3} | {} ({} / {}) | {:.3} | {diff} |",
                evs.len(),
                s.mean_curvature_variance,
                s.mean_curvature_roughness,
                r.sign_changes,
                r.hybrid_rings,
                r.rings,
                volume(&m) / v0,
            );
        }
    }
}

#[test]
#[ignore]
fn shrinkage_table() {
    let widths = [0.1, 0.25, 0.4, 0.5, 1.0];
    println!("volume after 3 levels / input volume, exact solves");
    println!(
        "| mesh | {} |",
        widths.map(|c| format!("c = {c}")).join(" | ")
    );
    println!("|---|{}", "---|".repeat(widths.len()));
    for name in CONTROL_MESHES {
        let coarse = load(name);
        let v0 = volume(&coarse);
        let cells: Vec<String> = widths
            .iter()
            .map(|&c| {
                let m = run(
                    &coarse,
                    SubdivOptions {
                        solver: Solver::Exact,
                        width: c,
                        levels: 3,
                        ..Default::default()
                    },
                );
                format!("{:.3}", volume(&m) / v0)
            })
            .collect();
        println!("| {name} | {} |", cells.join(" | "));
    }
    let coarse = load("sphere_highval");
    println!("\nsphere_highval curvature vs width (exact):");
    for c in widths {
        let m = run(
            &coarse,
            SubdivOptions {
                solver: Solver::Exact,
                width: c,
                levels: 3,
                ..Default::default()
            },
        );
        let s = curvature_stats(&m);
        println!(
            "c = {c}: var {:.4} roughness {:.4}",
            s.mean_curvature_variance, s.mean_curvature_roughness
        );
    }
}
