//! A scan-sized case end to end: `Pyramid::build_with` (hierarchy and analysis, its layout in a
//! temporary file above `MESHPYR_SPILL_MIB`) and an enhancement filter written back onto the
//! input, on a noisy bumpy torus of a million vertices (two million triangles). The peer
//! comparisons at 13M triangles, with peak memory, are `benches/compare/` and
//! docs/performance.md ("Scans of millions of vertices"). Run with `cargo bench --bench scale`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use meshpyr::mesh::PolygonMesh;
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{Filter, LevelSpec, Pyramid, PyramidOptions};
use std::hint::black_box;
use std::time::Duration;

/// A bumpy torus with `n·m` vertices and seeded noise of about a tenth of an edge.
fn noisy_torus(n: u32, m: u32) -> PolygonMesh {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let (pos, tris) = meshpyr::mesh::shapes::torus(n, m, |u, v| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let noise = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 6e-4;
        let r = 2.0 + (1.0 + 0.05 * (9.0 * u).sin() * (7.0 * v).cos() + noise) * v.cos();
        DVec3::new(r * u.cos(), r * u.sin(), v.sin())
    });
    PolygonMesh::from_triangles(pos, &tris)
}

fn bench(c: &mut Criterion) {
    let scan = noisy_torus(1000, 1000);
    let n = scan.n_vertices();
    let enhance =
        Filter::default().gain(LevelSpec::Vertices(n / 32), LevelSpec::Vertices(n / 2), 2.0);
    let mut g = c.benchmark_group("scale");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(60))
        .warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("build_and_enhance_1M_vertices", |b| {
        b.iter(|| {
            let pyramid = Pyramid::build_with(
                black_box(scan.clone()),
                &PyramidOptions::default(),
                &NoProgress,
            )
            .expect("a torus has a pyramid");
            pyramid.into_filtered(&enhance).mesh.n_vertices()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
