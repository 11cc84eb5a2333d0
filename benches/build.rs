//! Half-edge construction from indexed triangles (the builder alone; `io_read` adds parsing).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use meshpyr::mesh::{Mesh, PolygonMesh};
use std::hint::black_box;

/// A closed UV-sphere-like torus grid with `n*m*2` triangles (all vertices regular).
fn torus(n: u32, m: u32) -> PolygonMesh {
    let (pos, tris) = meshpyr::mesh::shapes::torus(n, m, |u, v| {
        let r = 2.0 + v.cos();
        DVec3::new(r * u.cos(), r * u.sin(), v.sin())
    });
    PolygonMesh::from_triangles(pos, &tris)
}

fn bench_build(c: &mut Criterion) {
    let mesh = torus(1000, 500); // 1,000,000 triangles
    let mut g = c.benchmark_group("build");
    g.sample_size(10);
    g.throughput(Throughput::Elements(mesh.n_faces() as u64));
    g.bench_function("halfedge_from_polygons_1M_tris", |b| {
        b.iter(|| Mesh::from_polygons(black_box(&mesh)).map(|b| b.mesh.n_faces()))
    });
    let bytes = meshpyr::io::write_mesh_bytes(
        &mesh,
        meshpyr::io::MeshFormat::Ply,
        &meshpyr::io::WriteOptions::default(),
    )
    .expect("writes");
    g.bench_function("binary_ply_read_and_build_1M_tris", |b| {
        b.iter(|| {
            let poly =
                meshpyr::io::read_mesh_bytes(black_box(&bytes), meshpyr::io::MeshFormat::Ply)
                    .expect("reads");
            Mesh::from_polygons(&poly).map(|b| b.mesh.n_faces())
        })
    });
    g.finish();
}

criterion_group!(benches, bench_build);
criterion_main!(benches);
