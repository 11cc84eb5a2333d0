//! Reads a mesh file and builds the half-edge mesh `N` times, printing the median wall time
//! per pass and the triangle throughput.
//!
//! `cargo run --release --example read_build_timing -- mesh.ply [N]`

use meshpyr::io;
use meshpyr::mesh::Mesh;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or_else(|| anyhow::anyhow!("usage: read_build_timing MESH [N]"))?;
    let n: usize = args.next().map_or(Ok(5), |s| s.parse())?;
    let bytes = std::fs::read(&path)?;
    let format = io::MeshFormat::from_path(std::path::Path::new(&path))?;
    let mut read = Vec::new();
    let mut build = Vec::new();
    let mut tris = 0;
    for _ in 0..n {
        let t0 = Instant::now();
        let poly = io::read_mesh_bytes(&bytes, format)?;
        let t1 = Instant::now();
        let built = Mesh::from_polygons(&poly)?;
        let t2 = Instant::now();
        tris = built.mesh.n_faces();
        read.push((t1 - t0).as_secs_f64());
        build.push((t2 - t1).as_secs_f64());
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (r, b) = (median(&mut read), median(&mut build));
    println!(
        "{tris} triangles: read {:.1} ms, build {:.1} ms, total {:.1} ms -> {:.2} M triangles/s",
        r * 1e3,
        b * 1e3,
        (r + b) * 1e3,
        tris as f64 / (r + b) / 1e6
    );
    Ok(())
}
