//! Prints the quality table of the subdivision README section (run manually:
//! `cargo test --release --test subdiv_report -- --ignored --nocapture`).

mod common;

use common::*;
use meshpyr::mesh::SlotIndex;
use meshpyr::metrics::curvature::{curvature_stats, gauss_curvature, ring_sign_changes};
use meshpyr::progress::NoProgress;
use meshpyr::subdiv::{Scheme, Solver, SubdivOptions, subdivide};

#[test]
#[ignore]
fn quality_table() {
    let levels = 3;
    println!(
        "| mesh | max valence | scheme | H var | H rough | hybrid rings / rings | sign changes | volume ratio |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for name in CONTROL_MESHES {
        let coarse = load(name);
        let maxval = coarse.vertices().map(|v| coarse.valence(v)).max().unwrap();
        let evs: Vec<_> = coarse
            .vertices()
            .filter(|&v| !coarse.is_boundary_vertex(v) && coarse.valence(v) >= 8)
            .collect();
        let v0 = volume(&coarse);
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
                "MCM exact c=.25",
                SubdivOptions {
                    solver: Solver::Exact,
                    levels,
                    ..Default::default()
                },
            ),
            (
                "MCM cg c=.25",
                SubdivOptions {
                    levels,
                    ..Default::default()
                },
            ),
            (
                "MCM exact local",
                SubdivOptions {
                    solver: Solver::Exact,
                    local_width: true,
                    levels,
                    ..Default::default()
                },
            ),
        ] {
            let out = subdivide(&coarse, &opts, &NoProgress).unwrap();
            let m = &out.mesh;
            let s = curvature_stats(m);
            let k = gauss_curvature(m);
            let ids: Vec<_> = m.vertices().collect();
            let centres: Vec<_> = evs.iter().map(|v| ids[v.slot()]).collect();
            let r = ring_sign_changes(m, &k, &centres, 1 << (levels - 1), 1e-2);
            println!(
                "| {name} | {maxval} ({} EVs ≥8) | {label} | {:.4} | {:.4} | {} / {} | {} | {:.3} |",
                evs.len(),
                s.mean_curvature_variance,
                s.mean_curvature_roughness,
                r.hybrid_rings,
                r.rings,
                r.sign_changes,
                volume(m) / v0
            );
        }
    }
}

#[test]
#[ignore]
fn explore() {
    let levels = 3;
    for name in [
        "cone20",
        "sphere_highval",
        "tripod",
        "torus_quad",
        "mushroom_quad",
    ] {
        let coarse = load(name);
        let evs: Vec<_> = coarse
            .vertices()
            .filter(|&v| !coarse.is_boundary_vertex(v) && coarse.valence(v) >= 8)
            .collect();
        let v0 = volume(&coarse);
        let diag = coarse.bbox_diagonal();
        for c in [0.25, 0.5, 1.0] {
            let ex = subdivide(
                &coarse,
                &SubdivOptions {
                    solver: Solver::Exact,
                    width: c,
                    levels,
                    ..Default::default()
                },
                &NoProgress,
            )
            .unwrap();
            for (label, solver, m) in [
                ("exact", Solver::Exact, 2),
                ("cg2", Solver::Cg, 2),
                ("cg6", Solver::Cg, 6),
                ("jac2", Solver::Jacobi, 2),
            ] {
                let out = subdivide(
                    &coarse,
                    &SubdivOptions {
                        solver,
                        width: c,
                        finest_steps: m,
                        levels,
                        ..Default::default()
                    },
                    &NoProgress,
                )
                .unwrap();
                let mm = &out.mesh;
                let s = curvature_stats(mm);
                let k = gauss_curvature(mm);
                let ids: Vec<_> = mm.vertices().collect();
                let centres: Vec<_> = evs.iter().map(|v| ids[v.slot()]).collect();
                let r = ring_sign_changes(mm, &k, &centres, 1 << (levels - 1), 1e-2);
                let d = mm
                    .positions()
                    .iter()
                    .zip(ex.mesh.positions())
                    .map(|(a, b)| (*a - b).length())
                    .fold(0.0, f64::max);
                let res: Vec<String> = out
                    .levels
                    .iter()
                    .map(|l| format!("{}:{:.0e}", l.steps, l.relative_residual))
                    .collect();
                println!(
                    "{name:15} c={c:.2} {label:6} var {:.3} rough {:.3} hyb {}/{} sc {:4} vol {:.3} diff/diag {:.4} [{}]",
                    s.mean_curvature_variance,
                    s.mean_curvature_roughness,
                    r.hybrid_rings,
                    r.rings,
                    r.sign_changes,
                    volume(mm) / v0,
                    d / diag,
                    res.join(" ")
                );
            }
        }
    }
}
