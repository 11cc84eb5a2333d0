//! The pyramid's and the `.pyr` format's speed figures in one run: the PM build, the analysis,
//! synthesis under the paper's three filters (enhancement ×2, low-pass and stop-band on levels
//! 1000–15000), `.pyr` save and load (bytes in memory). Each step runs `N` times in a row
//! (synthesis, save and load more often, being shorter); the minimum is the figure least
//! disturbed by other work on a shared machine, the median the typical one. Prints the ratios
//! the project's targets are stated in: analysis ÷ PM build, synthesis seconds per million
//! vertices, and save/load megabytes (10⁶ bytes) of file per second.
//!
//! `cargo run --release --example timings -- [MESH] [N]` (default: the bundled bunny, N = 10).

use meshpyr::PyramidOptions;
use meshpyr::format;
use meshpyr::mesh::Mesh;
use meshpyr::pm::{PmOptions, ProgressiveMesh};
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{DetailPyramid, Filter};
use meshpyr::relax::SecondDifference;
use std::path::PathBuf;
use std::time::Instant;

/// Minimum and median wall time in seconds of `runs` calls of `f`.
fn min_median(runs: usize, mut f: impl FnMut()) -> (f64, f64) {
    let mut t: Vec<f64> = (0..runs.max(1))
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    (t[0], t[t.len() / 2])
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let input = args.next().map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.ply"),
        PathBuf::from,
    );
    let runs: usize = args.next().map_or(Ok(10), |s| s.parse())?;
    let mesh_file = meshpyr::io::read_mesh(&input)?;
    let mesh = Mesh::from_polygons(&mesh_file)?.mesh;
    let info = PyramidOptions::default();
    let relax = SecondDifference::default();
    let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress)?;
    let pyramid = DetailPyramid::analyze(&pm, &relax, &NoProgress)?;
    let (bytes, _) = format::encode(&mesh_file, &pm, &info)?;
    println!(
        "{}: {} vertices, {} splits, .pyr file {} bytes; min / median of {runs} runs (synthesis, save, load: {})",
        input.display(),
        pm.n_vertices(),
        pm.splits().len(),
        bytes.len(),
        5 * runs
    );

    let build = min_median(runs, || {
        std::hint::black_box(
            ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).ok(),
        );
    });
    let analysis = min_median(runs, || {
        std::hint::black_box(DetailPyramid::analyze(&pm, &relax, &NoProgress).ok());
    });
    let ms = |(a, b): (f64, f64)| format!("{:9.2} / {:9.2} ms", a * 1e3, b * 1e3);
    println!("PM build              {}", ms(build));
    println!(
        "analysis              {}   {:.2} / {:.2} × the PM build",
        ms(analysis),
        analysis.0 / build.0,
        analysis.1 / build.1
    );

    let per_million = 1e6 / pyramid.n_vertices() as f64;
    for (name, _, filter) in Filter::paper_experiments() {
        let gains = filter.resolve(pyramid.surface_area());
        let t = min_median(5 * runs, || {
            std::hint::black_box(pyramid.synthesize(&gains));
        });
        println!(
            "synthesis, {name:11}{}   {:.3} / {:.3} s per million vertices",
            ms(t),
            t.0 * per_million,
            t.1 * per_million
        );
    }

    let megabytes = bytes.len() as f64 / 1e6;
    let save = min_median(5 * runs, || {
        std::hint::black_box(format::encode(&mesh_file, &pm, &info).ok());
    });
    let load = min_median(5 * runs, || {
        std::hint::black_box(format::decode(&bytes).ok());
    });
    for (name, t) in [("save", save), ("load", load)] {
        println!(
            "{name:22}{}   {:.0} / {:.0} MB/s",
            ms(t),
            megabytes / t.0,
            megabytes / t.1
        );
    }
    Ok(())
}
