//! Cost of the denoising baselines and the error metrics.
//!
//! - `taubin_10`: 10 Taubin λ|μ iterations (each weighting) on the noisy fandisk Loop-subdivided
//!   twice (207k faces);
//! - `mcf_1`: one implicit MCF step (assembly + sparse Cholesky) on the same mesh;
//! - `compare_bunny`: `metrics::compare` of the noisy bunny (75k faces) against the bunny
//!   (BVH builds, E_v, E_n and both Hausdorff sides).
//!
//! `cargo bench --bench smooth_baselines` (add `-- --quick` for a fast look).

use criterion::{Criterion, criterion_group, criterion_main};
use meshpyr::mesh::Mesh;
use meshpyr::progress::NoProgress;
use meshpyr::smooth::{McfOptions, TaubinOptions, Weights, implicit_mcf, taubin_smoothing};
use std::hint::black_box;

fn load(name: &str) -> Mesh {
    let path = format!("{}/tests/data/{name}.ply", env!("CARGO_MANIFEST_DIR"));
    let poly = meshpyr::io::read_mesh(std::path::Path::new(&path)).expect("test mesh");
    Mesh::from_polygons(&poly).expect("valid mesh").mesh
}

fn bench(c: &mut Criterion) {
    let mut big = load("fandisk_noise_n020");
    for _ in 0..2 {
        big = meshpyr::subdiv::loop_step(&big).expect("loop step");
    }
    assert!(big.n_faces() >= 100_000);
    let mut group = c.benchmark_group("smooth_207k_faces");
    group.sample_size(10);
    for (label, weights) in [
        ("taubin_10_uniform", Weights::Uniform),
        ("taubin_10_inverse_edge", Weights::InverseEdgeLength),
        ("taubin_10_cotan", Weights::Cotangent),
    ] {
        let o = TaubinOptions {
            iterations: 10,
            weights,
            ..Default::default()
        };
        group.bench_function(label, |b| {
            b.iter(|| black_box(taubin_smoothing(&big, &o, &NoProgress).expect("taubin")))
        });
    }
    group.bench_function("mcf_1", |b| {
        b.iter(|| black_box(implicit_mcf(&big, &McfOptions::default(), &NoProgress).expect("mcf")))
    });
    group.finish();

    let bunny = load("bunny");
    let noisy = load("bunny_noise_n020");
    let mut group = c.benchmark_group("metrics");
    group.sample_size(10);
    group.bench_function("compare_bunny", |b| {
        b.iter(|| black_box(meshpyr::metrics::compare(&noisy, &bunny).expect("compare")))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
