//! Denoising cost on a ≥100k-face scan-like mesh: a UV sphere with 0.2 L of deterministic
//! normal noise (256 × 200 segments, 102 144 faces). Target: the default (`auto`) ≤ 2 s on
//! two cores.
//!
//! `cargo bench --bench smooth` (add `-- --quick` for a fast look).

use criterion::{Criterion, criterion_group, criterion_main};
use meshpyr::mesh::Mesh;
use meshpyr::progress::NoProgress;
use meshpyr::smooth::{DenoiseOptions, denoise};
use std::hint::black_box;

fn noisy_sphere(nu: usize, nv: usize) -> Mesh {
    let hash = |i: usize| {
        let x = (i as f64 * 12.9898).sin() * 43758.5453;
        x - x.floor() - 0.5
    };
    let edge = std::f64::consts::PI / nv as f64;
    let (p, t) = meshpyr::mesh::shapes::uv_sphere(nu, nv, |k, _, _| 1.0 + 0.7 * edge * hash(k));
    Mesh::from_triangles(&p, &t).expect("valid sphere").mesh
}

fn bench(c: &mut Criterion) {
    let mesh = noisy_sphere(256, 200);
    assert!(mesh.n_faces() >= 100_000);
    let mut group = c.benchmark_group("smooth_sphere_102k");
    group.sample_size(10);
    for (label, options) in [
        ("auto", DenoiseOptions::automatic()),
        ("adaptive", DenoiseOptions::adaptive()),
        ("anisotropic", DenoiseOptions::anisotropic()),
    ] {
        group.bench_function(label, |b| {
            b.iter(|| black_box(denoise(&mesh, &options, &NoProgress).expect("denoises")))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
