//! Times re-filtering (synthesis) on a mesh, reporting thread CPU time per split so that a
//! loaded machine does not distort the number: `cargo run --release --example synth_timing -- [IN]`.

use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{Filter, LevelSpec, PyramidOptions, ScanPyramid};
use meshpyr::relax::SecondDifference;
use std::path::PathBuf;

/// User CPU seconds of this thread (Linux `/proc/thread-self/stat`, 10 ms ticks); wall time
/// elsewhere.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    Some(utime / 100.0)
}

fn main() -> anyhow::Result<()> {
    let input = std::env::args().nth(1).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.ply"),
        PathBuf::from,
    );
    let scan = ScanPyramid::build(
        meshpyr::io::read_mesh(&input)?,
        &SecondDifference::default(),
        &PyramidOptions::default(),
        &NoProgress,
    )?;
    let p = &scan.pyramid;
    let gains = Filter::default()
        .gain(LevelSpec::Vertices(1000), LevelSpec::Vertices(15000), 2.0)
        .resolve(p.surface_area());
    let runs = 30;
    let (c0, w0) = (cpu_seconds(), std::time::Instant::now());
    for _ in 0..runs {
        std::hint::black_box(p.synthesize(&gains));
    }
    let wall = w0.elapsed().as_secs_f64() / runs as f64;
    let cpu = cpu_seconds().zip(c0).map(|(a, b)| (a - b) / runs as f64);
    let per_million = |t: f64| t / p.n_splits() as f64 * 1e6;
    println!(
        "{} splits: synthesis wall {:.1} ms ({:.3} s per million), thread CPU {}",
        p.n_splits(),
        wall * 1e3,
        per_million(wall),
        cpu.map_or("n/a".into(), |c| format!(
            "{:.1} ms ({:.3} s per million)",
            c * 1e3,
            per_million(c)
        ))
    );
    println!("pyramid memory: {:.1} MB", p.memory_bytes() as f64 / 1e6);
    Ok(())
}
