//! Progressive-mesh build and simplification.
//!
//! `simplify_*` runs the library part of `meshpyr simplify`: the builder's repairs (a corner
//! table, no half-edge records), decimation and output assembly, without file IO. Set `MESHPYR_BIG=/path/to/big.ply` (made by
//! `benches/compare/make_big.py`) to also time the 832k-triangle benchmark mesh; the
//! meshoptimizer baseline is timed by `benches/compare/meshopt_simplify.py` in the same session.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use meshpyr::io::read_mesh;
use meshpyr::mesh::Mesh;
use meshpyr::pm::{PmOptions, ProgressiveMesh, SimplifyTarget, simplify};
use meshpyr::progress::NoProgress;
use std::hint::black_box;
use std::path::Path;

fn bench_pm(c: &mut Criterion) {
    let bunny =
        read_mesh(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.ply")).unwrap();
    let mesh = Mesh::from_polygons(&bunny).unwrap().mesh;
    let mut g = c.benchmark_group("pm");
    g.sample_size(10);
    g.throughput(Throughput::Elements(bunny.n_faces() as u64));
    g.bench_function("build_full_hierarchy_bunny_75k", |b| {
        b.iter(|| {
            ProgressiveMesh::build(black_box(&mesh), &PmOptions::default(), &NoProgress)
                .unwrap()
                .n_base_vertices()
        })
    });
    let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
    g.bench_function("cursor_finest_to_base_to_finest_bunny", |b| {
        b.iter(|| {
            let mut cur = pm.cursor();
            cur.seek(pm.n_base_vertices());
            cur.seek(pm.n_vertices());
            cur.level()
        })
    });
    g.bench_function("simplify_bunny_to_1pct", |b| {
        b.iter(|| {
            simplify(
                black_box(&bunny),
                SimplifyTarget::Ratio(0.01),
                &PmOptions::default(),
                &NoProgress,
            )
            .unwrap()
            .mesh
            .n_faces()
        })
    });
    if let Some(big) = std::env::var_os("MESHPYR_BIG") {
        let big = read_mesh(Path::new(&big)).unwrap();
        g.throughput(Throughput::Elements(big.n_faces() as u64));
        g.bench_function("simplify_big_to_1pct", |b| {
            b.iter(|| {
                simplify(
                    black_box(&big),
                    SimplifyTarget::Ratio(0.01),
                    &PmOptions::default(),
                    &NoProgress,
                )
                .unwrap()
                .mesh
                .n_faces()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_pm);
criterion_main!(benches);
