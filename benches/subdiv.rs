//! Subdivision cost: cascadic MCM (CG schedule) should be linear in the output size (4×
//! vertices → ≤ 4.4× time) and within 2× of Loop at the same output size.
//!
//! `cargo bench --bench subdiv` (add `-- --quick` for a fast look).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use meshpyr::mesh::Mesh;
use meshpyr::progress::NoProgress;
use meshpyr::subdiv::{Scheme, Solver, SubdivOptions, subdivide};
use std::hint::black_box;

fn load(name: &str) -> Mesh {
    let path = format!("{}/tests/data/{name}.ply", env!("CARGO_MANIFEST_DIR"));
    let poly = meshpyr::io::read_mesh(std::path::Path::new(&path)).expect("test mesh");
    Mesh::from_polygons(&poly).expect("valid mesh").mesh
}

fn bench(c: &mut Criterion) {
    let coarse = load("mushroom_quad");
    let mut group = c.benchmark_group("subdiv_mushroom");
    group.sample_size(10);
    for levels in [3usize, 4, 5] {
        for (label, scheme, solver) in [
            ("mcm_cg", Scheme::Mcm, Solver::Cg),
            ("mcm_jacobi", Scheme::Mcm, Solver::Jacobi),
            ("loop", Scheme::Loop, Solver::Cg),
        ] {
            let opts = SubdivOptions {
                levels,
                scheme,
                solver,
                ..Default::default()
            };
            group.bench_with_input(BenchmarkId::new(label, levels), &opts, |b, o| {
                b.iter(|| black_box(subdivide(&coarse, o, &NoProgress).expect("subdivides")))
            });
        }
        if levels <= 4 {
            let opts = SubdivOptions {
                levels,
                solver: Solver::Exact,
                ..Default::default()
            };
            group.bench_with_input(BenchmarkId::new("mcm_exact", levels), &opts, |b, o| {
                b.iter(|| black_box(subdivide(&coarse, o, &NoProgress).expect("subdivides")))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
