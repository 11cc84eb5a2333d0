//! Rough per-stage timing of one subdivision level (diagnostics for the bench numbers):
//! `cargo run --release --example subdiv_timing -- tests/data/mushroom_quad.ply 5`.

use meshpyr::mesh::Mesh;
use meshpyr::numerics::fem::{cotangent_stiffness, lumped_mass, system_matrix};
use meshpyr::subdiv::refine::quadrisect;
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .unwrap_or_else(|| "tests/data/mushroom_quad.ply".into());
    let levels: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(5);
    let poly = meshpyr::io::read_mesh(std::path::Path::new(&path)).expect("mesh");
    let mut mesh = Mesh::from_polygons(&poly).expect("build").mesh;
    for level in 1..=levels {
        let t = Instant::now();
        let r = quadrisect(&mesh).expect("refine");
        let t_refine = t.elapsed();
        let t = Instant::now();
        let (p, tris) = r.mesh.to_triangles();
        let t_copy = t.elapsed();
        let t = Instant::now();
        let _ = Mesh::from_triangles(&p, &tris).expect("build");
        let t_build = t.elapsed(); // the generic builder, for comparison
        let t = Instant::now();
        let pos = r.mesh.positions();
        let mass = lumped_mass(&r.triangles, &pos);
        let l = cotangent_stiffness(&r.triangles, &pos, None);
        let a = system_matrix(&mass, l, 0.1);
        let t_asm = t.elapsed();
        let x: Vec<[f64; 3]> = pos.iter().map(|q| q.to_array()).collect();
        let mut y = x.clone();
        let t = Instant::now();
        a.mul(&x, &mut y);
        let t_mul = t.elapsed();
        println!(
            "level {level}: {} V, refine(incl. build) {:?}, to_triangles {:?}, build alone {:?}, assemble {:?}, one matvec {:?}",
            r.mesh.n_vertices(),
            t_refine,
            t_copy,
            t_build,
            t_asm,
            t_mul
        );
        mesh = r.mesh;
    }
}
