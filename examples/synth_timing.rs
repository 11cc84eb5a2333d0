//! Times re-filtering (synthesis) on a mesh, reporting CPU time per split so that a loaded
//! machine does not distort the number, plus the analysis against the PM build (CPU time of the
//! whole process, all threads, and wall time: the PM build's candidate scan and the analysis's
//! records run on rayon's workers; median of 3) and the pyramid's memory per vertex:
//! `cargo run --release --example synth_timing -- [IN]`.

use meshpyr::mesh::Mesh;
use meshpyr::pm::{PmOptions, ProgressiveMesh};
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{DetailPyramid, Filter, LevelSpec, Pyramid, PyramidOptions};
use meshpyr::relax::SecondDifference;
use std::io::Write;
use std::path::PathBuf;

/// User + system CPU seconds of the whole process, all threads (Linux `/proc/self/stat`,
/// 10 ms ticks). Work handed to rayon's workers counts too, which a per-thread clock would
/// miss.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

fn main() -> anyhow::Result<()> {
    // Write errors (a closed pipe) end the program with an error instead of a panic.
    let mut out = std::io::stdout().lock();
    let input = std::env::args().nth(1).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.ply"),
        PathBuf::from,
    );
    let scan = Pyramid::build_with(
        meshpyr::io::read_mesh(&input)?,
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
    writeln!(
        out,
        "{} splits: synthesis wall {:.1} ms ({:.3} s per million), CPU {}",
        p.n_splits(),
        wall * 1e3,
        per_million(wall),
        cpu.map_or("n/a".into(), |c| format!(
            "{:.1} ms ({:.3} s per million)",
            c * 1e3,
            per_million(c)
        ))
    )?;
    writeln!(
        out,
        "pyramid memory: {:.1} MB ({:.0} bytes per vertex)",
        p.memory_bytes() as f64 / 1e6,
        p.memory_bytes() as f64 / p.n_vertices() as f64
    )?;
    // Analysis vs PM build, process CPU and wall time, median of 3.
    let mesh = Mesh::from_polygons(&meshpyr::io::read_mesh(&input)?)?.mesh;
    let median = |mut t: Vec<f64>| {
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    };
    // (process CPU, wall) seconds, each the median of 3 runs.
    let time = |f: &mut dyn FnMut()| {
        let (cpu, wall): (Vec<f64>, Vec<f64>) = (0..3)
            .map(|_| {
                let (c0, w0) = (cpu_seconds().unwrap_or(0.0), std::time::Instant::now());
                f();
                (
                    cpu_seconds().unwrap_or(0.0) - c0,
                    w0.elapsed().as_secs_f64(),
                )
            })
            .unzip();
        (median(cpu), median(wall))
    };
    let pm_opts = PmOptions::default();
    let build = time(&mut || {
        std::hint::black_box(ProgressiveMesh::build(&mesh, &pm_opts, &NoProgress).ok());
    });
    let pm = ProgressiveMesh::build(&mesh, &pm_opts, &NoProgress)?;
    let relax = SecondDifference::default();
    let analysis = time(&mut || {
        std::hint::black_box(DetailPyramid::analyze(&pm, &relax, &NoProgress).ok());
    });
    writeln!(
        out,
        "process CPU: PM build {:.0} ms, analysis {:.0} ms ({:.2}x the PM build)",
        build.0 * 1e3,
        analysis.0 * 1e3,
        analysis.0 / build.0
    )?;
    writeln!(
        out,
        "wall: PM build {:.0} ms, analysis {:.0} ms ({:.2}x the PM build)",
        build.1 * 1e3,
        analysis.1 * 1e3,
        analysis.1 / build.1
    )?;
    Ok(())
}
