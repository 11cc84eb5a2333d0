//! Denoising cost on a ≥100k-face scan-like mesh: a UV sphere with 0.2 L of deterministic
//! normal noise (256 × 200 segments, 102 144 faces). Target: adaptive default ≤ 2 s on two
//! cores.
//!
//! `cargo bench --bench smooth` (add `-- --quick` for a fast look).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
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
    let mut p = vec![DVec3::Z, -DVec3::Z];
    for j in 1..nv {
        let th = std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..nu {
            let ph = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
            let r = 1.0 + 0.7 * edge * hash(p.len());
            p.push(r * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
        }
    }
    let id = |i: usize, j: usize| (2 + (j - 1) * nu + i % nu) as u32;
    let mut t = Vec::new();
    for i in 0..nu {
        t.push([0, id(i, 1), id(i + 1, 1)]);
        t.push([1, id(i + 1, nv - 1), id(i, nv - 1)]);
        for j in 1..nv - 1 {
            t.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    Mesh::from_triangles(&p, &t).expect("valid sphere").mesh
}

fn bench(c: &mut Criterion) {
    let mesh = noisy_sphere(256, 200);
    assert!(mesh.n_faces() >= 100_000);
    let mut group = c.benchmark_group("smooth_sphere_102k");
    group.sample_size(10);
    for (label, options) in [
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
