//! Binary PLY read throughput: a ≥ 1M-triangle grid written as binary little-endian PLY bytes,
//! parsed with `read_mesh_bytes`. Reports triangles per second (criterion "elements").
//!
//! `cargo bench --bench io_read` (add `-- --quick` for a short run).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use meshpyr::io::{MeshFormat, WriteOptions, read_mesh_bytes, write_mesh_bytes};
use meshpyr::mesh::{PolygonMesh, ScalarType};

/// An n × n vertex grid on a wavy surface: 2 (n − 1)² triangles.
fn grid(n: u32) -> PolygonMesh {
    let mut positions = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            let z = 0.05 * (12.0 * x).sin() * (9.0 * y).cos();
            positions.push(DVec3::new(x, y, z).as_vec3().as_dvec3());
        }
    }
    let mut tris = Vec::with_capacity((2 * (n - 1) * (n - 1)) as usize);
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v = j * n + i;
            tris.push([v, v + 1, v + n + 1]);
            tris.push([v, v + n + 1, v + n]);
        }
    }
    let mut m = PolygonMesh::from_triangles(positions, &tris);
    m.position_type = Some(ScalarType::F32);
    m
}

fn bench(c: &mut Criterion) {
    let mesh = grid(709); // 2 · 708² = 1,002,528 triangles
    let tris = mesh.n_faces() as u64;
    let bytes = write_mesh_bytes(&mesh, MeshFormat::Ply, &WriteOptions::default()).unwrap();
    let mut g = c.benchmark_group("io_read");
    g.throughput(Throughput::Elements(tris));
    g.sample_size(20);
    g.bench_function("binary_le_ply_1M_triangles", |b| {
        b.iter(|| {
            let m = read_mesh_bytes(std::hint::black_box(&bytes), MeshFormat::Ply).unwrap();
            assert_eq!(m.n_faces() as u64, tris);
            m
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
