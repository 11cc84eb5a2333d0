//! Detail pyramid: analysis and synthesis against the PM build, at growing sizes (linearity),
//! plus the bundled bunny scan. Synthesis runs the paper's low-pass, stop-band and enhancement
//! filters (`synthesis_lowpass`, `synthesis_stopband`, `synthesis_enhanced`). Run with
//! `cargo bench --bench pyramid`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use meshpyr::mesh::{Mesh, PolygonMesh};
use meshpyr::pm::{PmOptions, ProgressiveMesh};
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{DetailPyramid, Filter};
use meshpyr::relax::SecondDifference;
use std::hint::black_box;
use std::time::Duration;

/// A bumpy, slightly noisy torus with `n·m` vertices.
fn torus(n: u32, m: u32) -> Mesh {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let (pos, tris) = meshpyr::mesh::shapes::torus(n, m, |u, v| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let noise = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.002;
        let r = 2.0 + (1.0 + 0.05 * (7.0 * u).sin() * (5.0 * v).cos() + noise) * v.cos();
        DVec3::new(r * u.cos(), r * u.sin(), v.sin())
    });
    Mesh::from_polygons(&PolygonMesh::from_triangles(pos, &tris))
        .unwrap()
        .mesh
}

fn bunny() -> Mesh {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.ply");
    let poly = meshpyr::io::read_mesh(&path).unwrap();
    Mesh::from_polygons(&poly).unwrap().mesh
}

fn bench(c: &mut Criterion) {
    let relax = SecondDifference::default();
    let mut cases: Vec<(String, Mesh)> = [(100u32, 100u32), (200, 100), (200, 200)]
        .iter()
        .map(|&(n, m)| (format!("torus{}k", n * m / 1000), torus(n, m)))
        .collect();
    cases.push(("bunny38k".into(), bunny()));
    let mut g = c.benchmark_group("pyramid");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500));
    for (name, mesh) in &cases {
        let nv = mesh.n_vertices() as u64;
        g.throughput(Throughput::Elements(nv));
        g.bench_with_input(BenchmarkId::new("pm_build", name), mesh, |b, m| {
            b.iter(|| ProgressiveMesh::build(black_box(m), &PmOptions::default(), &NoProgress))
        });
        let pm = ProgressiveMesh::build(mesh, &PmOptions::default(), &NoProgress).unwrap();
        g.bench_with_input(BenchmarkId::new("analysis", name), &pm, |b, pm| {
            b.iter(|| DetailPyramid::analyze(black_box(pm), &relax, &NoProgress).unwrap())
        });
        let pyr = DetailPyramid::analyze(&pm, &relax, &NoProgress).unwrap();
        // The paper's three Venus filters: enhancement (every level still needs its frames),
        // low-pass and stop-band (removed levels skip them).
        for (filter_name, _, filter) in Filter::paper_experiments() {
            let gains = filter.resolve(pyr.surface_area());
            let id = format!("synthesis_{filter_name}");
            g.bench_with_input(BenchmarkId::new(id, name), &pyr, |b, p| {
                b.iter(|| black_box(p).synthesize(&gains))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
