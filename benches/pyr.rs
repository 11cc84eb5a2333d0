//! `.pyr` save and load speed (MB/s of file), on the bundled bunny and, when
//! `MESHPYR_BIG_MESH` names a mesh file (e.g. the bunny Loop-subdivided twice, ~600k vertices),
//! on that too. Save = `format::encode` (bytes in memory, the splits replayed once to code the
//! wings). Load = `format::decode` from bytes in memory to the validated `ProgressiveMesh` and
//! the user's exact `PolygonMesh` (the splits replayed once on flat arrays; the half-edge mesh
//! is built only for inputs the builder repairs). `load_level_finest` = `read_level` (the
//! progressive part only). File reading/writing is not included; the pyramid re-analysis
//! that follows a load for `filter`/`spectrum`/`edit` is measured separately.
//! Run with `cargo bench --bench pyr`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use meshpyr::PyramidOptions;
use meshpyr::format;
use meshpyr::mesh::{Mesh, PolygonMesh};
use meshpyr::pm::ProgressiveMesh;
use meshpyr::progress::NoProgress;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

fn inputs() -> Vec<(String, PolygonMesh)> {
    let mut v = Vec::new();
    let bunny = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.ply");
    v.push(("bunny".to_string(), meshpyr::io::read_mesh(&bunny).unwrap()));
    if let Some(p) = std::env::var_os("MESHPYR_BIG_MESH") {
        let p = PathBuf::from(p);
        v.push(("big".to_string(), meshpyr::io::read_mesh(&p).unwrap()));
    }
    v
}

fn bench(c: &mut Criterion) {
    for (name, input) in inputs() {
        let info = PyramidOptions::default();
        let built = Mesh::from_polygons(&input).unwrap();
        let pm = ProgressiveMesh::build(&built.mesh, &info.pm, &NoProgress).unwrap();
        let (bytes, sizes) = format::encode(&input, &pm, &info).unwrap();
        let n = input.n_vertices() as f64;
        eprintln!(
            "{name}: {} vertices, {} bytes = {:.2} B/vertex (PM connectivity {:.2}, split errors {:.2}, positions {:.2}, order+polygons+attributes {:.2})",
            input.n_vertices(),
            bytes.len(),
            bytes.len() as f64 / n,
            sizes.pm_connectivity as f64 / n,
            sizes.split_errors as f64 / n,
            sizes.positions as f64 / n,
            sizes.trailing as f64 / n
        );
        let mut g = c.benchmark_group(format!("pyr/{name}"));
        g.sample_size(10)
            .measurement_time(Duration::from_secs(8))
            .throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function("save", |b| {
            b.iter(|| format::encode(black_box(&input), &pm, &info).unwrap())
        });
        g.bench_function("load", |b| {
            b.iter(|| format::decode(black_box(&bytes)).unwrap())
        });
        g.bench_function("load_level_finest", |b| {
            b.iter(|| format::read_level(black_box(&bytes), None).unwrap())
        });
        let data = format::decode(&bytes).unwrap();
        g.bench_function("reanalysis", |b| {
            b.iter(|| data.clone().into_pyramid(&NoProgress).unwrap())
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
