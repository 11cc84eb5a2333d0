//! MCM (CG schedule) against Loop at the same output size, run alternately so both see the
//! same machine load: `cargo run --release --example subdiv_ratio -- LEVELS RUNS [MESH]`
//! (defaults 3, 50, tests/data/mushroom_quad.ply). Prints the medians and the median ratio.

use meshpyr::mesh::Mesh;
use meshpyr::progress::NoProgress;
use meshpyr::subdiv::{Scheme, SubdivOptions, subdivide};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut args = std::env::args().skip(1);
    let levels: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(3);
    let runs: usize = args
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or(50)
        .max(1);
    let path = args
        .next()
        .unwrap_or_else(|| "tests/data/mushroom_quad.ply".into());
    let poly = meshpyr::io::read_mesh(std::path::Path::new(&path)).expect("mesh");
    let mesh = Mesh::from_polygons(&poly).expect("build").mesh;
    let time = |scheme| {
        let options = SubdivOptions {
            levels,
            scheme,
            ..Default::default()
        };
        let start = Instant::now();
        std::hint::black_box(subdivide(&mesh, &options, &NoProgress).expect("subdivides"));
        start.elapsed().as_secs_f64() * 1e3
    };
    let (mut mcm, mut lp, mut ratio) = (vec![], vec![], vec![]);
    for _ in 0..runs {
        let (a, b) = (time(Scheme::Mcm), time(Scheme::Loop));
        mcm.push(a);
        lp.push(b);
        ratio.push(a / b);
    }
    println!(
        "level {levels}: MCM {:.3} ms, Loop {:.3} ms, median ratio {:.2} ({runs} runs)",
        median(mcm),
        median(lp),
        median(ratio)
    );
}
