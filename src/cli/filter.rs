//! `meshpyr filter IN -o OUT [--lowpass N] [--stopband A:B] [--enhance A:B=G] [--gain A:B=G]
//! [--normal-only] [--relax …]`: band filters on the detail pyramid.
//!
//! Also holds what the pyramid subcommands share: loading a mesh into a [`ScanPyramid`] with a
//! progress bar.

use super::{BarProgress, Global};
use crate::io;
use crate::pyramid::{
    Filter, GainBand, LevelGains, LevelSpec, Pyramid, PyramidOptions, ScanPyramid,
};
use crate::relax::{RelaxKind, Relaxation, RelaxationSpec, SecondDifference};
use anyhow::Context;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Reads `path` and builds its progressive mesh and pyramid, reporting progress and timing;
/// returns it with the relaxation it was analysed with. `relax` defaults to the
/// second-difference operator. A `.pyr` file (detected by its signature) is loaded instead and
/// analysed with the relaxation recorded in it; asking for another one is an error.
pub fn load_pyramid(
    path: &Path,
    relax: Option<RelaxKind>,
    global: &Global,
) -> anyhow::Result<(ScanPyramid, RelaxationSpec)> {
    let wanted = relax.map(RelaxKind::spec);
    if super::build::is_pyr_file(path) {
        let (scan, spec) = super::build::load_pyr_scan(path, global)?;
        if let Some(w) = wanted
            && w != spec
        {
            anyhow::bail!(
                "{} was built with --relax {}; rebuild it with `meshpyr build --relax {}` to use that operator",
                path.display(),
                spec.name(),
                w.name()
            );
        }
        return Ok((scan, spec));
    }
    let spec = wanted.unwrap_or_default();
    let input = io::read_mesh(path)?;
    let scan = build_pyramid(
        input,
        spec.operator().as_ref(),
        &path.display().to_string(),
        global,
    )?;
    Ok((scan, spec))
}

/// Builds the pyramid of an already-read mesh; `name` is used in messages.
pub fn build_pyramid(
    input: crate::mesh::PolygonMesh,
    relaxation: &dyn Relaxation,
    name: &str,
    global: &Global,
) -> anyhow::Result<ScanPyramid> {
    let start = Instant::now();
    let bar = global.progress("pyramid");
    let scan = ScanPyramid::build(
        input,
        relaxation,
        &PyramidOptions::default(),
        &BarProgress(&bar),
    )
    .with_context(|| format!("cannot build the detail pyramid of {name}"))?;
    bar.finish_and_clear();
    let p = &scan.pyramid;
    global.say(format_args!(
        "{name}: {} vertices, levels {}..={}, {} details ({} relaxation) in {:.2} s",
        scan.input.positions.len(),
        p.n_base_vertices(),
        p.n_vertices(),
        p.n_details(),
        p.relaxation(),
        start.elapsed().as_secs_f64()
    ));
    Ok(scan)
}

fn parse_band(s: &str) -> Result<(LevelSpec, LevelSpec), String> {
    GainBand::parse_band(s).map_err(|e| e.to_string())
}

fn parse_gain_band(s: &str) -> Result<GainBand, String> {
    GainBand::parse_with_gain(s).map_err(|e| e.to_string())
}

/// The filter options shared by `filter` and `edit`.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct FilterOptions {
    /// Zero the details of every level above N (a vertex count, or a feature size in model
    /// units with a `u` suffix such as 0.01u).
    #[arg(long, value_name = "N")]
    pub lowpass: Option<LevelSpec>,
    /// Zero the details of the levels in (A, B] (repeatable).
    #[arg(long, value_name = "A:B", value_parser = parse_band)]
    pub stopband: Vec<(LevelSpec, LevelSpec)>,
    /// Multiply the details of the levels in (A, B] by G (repeatable).
    #[arg(long, value_name = "A:B=G", value_parser = parse_gain_band)]
    pub enhance: Vec<GainBand>,
    /// Generic gain band, same as --enhance (repeatable; gains of overlapping bands multiply).
    #[arg(long, value_name = "A:B=G", value_parser = parse_gain_band)]
    pub gain: Vec<GainBand>,
    /// Apply the gains to the normal component of the details only (no tangential drift).
    #[arg(long)]
    pub normal_only: bool,
}

impl FilterOptions {
    /// The filter these options describe.
    pub fn filter(&self) -> Filter {
        let mut f = Filter {
            normal_only: self.normal_only,
            ..Filter::default()
        };
        if let Some(n) = self.lowpass {
            f = f.lowpass(n);
        }
        for &(a, b) in &self.stopband {
            f = f.stopband(a, b);
        }
        f.bands
            .extend(self.enhance.iter().chain(&self.gain).copied());
        f
    }
}

/// `filter` resolved on `pyramid`, with a warning on standard error for every band that
/// selects none of the pyramid's levels (an empty band, a stop-band above the finest level, a
/// feature size finer than the scan's sampling), which would otherwise change nothing without
/// a word, and for every band that reaches below the coarsest level (a low-pass to fewer
/// vertices than the base has), which would otherwise silently do less. `name` is the input,
/// for the message.
pub fn resolve_reporting(filter: &Filter, pyramid: &Pyramid, name: &str) -> LevelGains {
    let gains = filter.resolve(pyramid.surface_area());
    // Splits create the levels (base, finest]; a band (a, b] reaches them when it is not
    // empty and overlaps them.
    let (base, finest) = (pyramid.n_base_vertices(), pyramid.n_vertices());
    for (band, &(a, b, gain)) in filter.bands.iter().zip(&gains.bands) {
        if gain == 1.0 {
            continue;
        }
        let (what, selects) = match band.to {
            Some(to) => (
                format!("band {}:{to}", band.from),
                format!("levels {}..={b}", a + 1),
            ),
            None => (
                format!("low-pass {}", band.from),
                format!("levels above {a}"),
            ),
        };
        if a >= b {
            eprintln!("warning: {name}: {what} is empty; it changes nothing");
        } else if a >= finest || b <= base {
            eprintln!(
                "warning: {name}: {what} selects {selects}, but the pyramid's levels are \
                 {}..={finest}; it changes nothing",
                base + 1
            );
        } else if a < base {
            eprintln!(
                "warning: {name}: {what} reaches below the pyramid's coarsest level, {base} \
                 vertices (no legal collapse goes further); levels {}..={base} do not exist, so \
                 it acts on levels {}..={} only",
                a + 1,
                base + 1,
                b.min(finest)
            );
        }
    }
    gains
}

/// Arguments of `meshpyr filter`.
#[derive(clap::Args, Debug)]
pub struct FilterArgs {
    /// Input mesh (.obj, .ply, .off, .stl) or .pyr file.
    pub input: PathBuf,
    /// Output mesh: the input's vertices and faces in the same order, new positions.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub filters: FilterOptions,
    /// Relaxation operator used for the prediction (default second-difference; a .pyr input
    /// uses the one it was built with).
    #[arg(long, value_enum)]
    pub relax: Option<RelaxKind>,
}

/// Runs `meshpyr filter`.
pub fn run(args: FilterArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let filter = args.filters.filter();
    if filter.bands.is_empty() {
        anyhow::bail!(
            "no filter given: use --lowpass N, --stopband A:B, --enhance A:B=G or --gain A:B=G"
        );
    }
    let (scan, _) = load_pyramid(&args.input, args.relax, global)?;
    let start = Instant::now();
    let gains = resolve_reporting(&filter, &scan.pyramid, &args.input.display().to_string());
    let out = scan.pyramid.synthesize(&gains);
    let mesh = scan.output_mesh(&out);
    global.say(format_args!(
        "synthesised {} levels in {:.3} s",
        scan.pyramid.n_splits(),
        start.elapsed().as_secs_f64()
    ));
    io::write_mesh(&args.output, &mesh)?;
    global.say(format_args!("wrote {}", args.output.display()));
    Ok(())
}

/// The pyramid part of `meshpyr demo`: the paper's three Venus experiments (low-pass above
/// level 1000, stop-band 1000–15000, enhancement ×2 on 1000–15000) on `input`, with the
/// spectrum of each result and previews, written into `dir` with file names starting `stem`.
pub fn demo_filters(
    input: crate::mesh::PolygonMesh,
    stem: &str,
    dir: &Path,
    global: &Global,
) -> anyhow::Result<()> {
    use crate::pyramid::Pyramid;
    use crate::render::{RenderOptions, Triangles, render_panels};

    let relaxation = SecondDifference::default();
    let scan = build_pyramid(input, &relaxation, stem, global)?;
    // The hierarchy, saved: `filter`, `spectrum` and `edit` take it instead of the mesh.
    let (bytes, sizes) = super::build::encode_pyr(&scan.input, &scan.pm, relaxation.into())?;
    let pyr_path = dir.join(format!("{stem}.pyr"));
    io::write_atomic(&pyr_path, &bytes)?;
    global.say(format_args!(
        "saved the hierarchy: wrote {} ({:.1} bytes/vertex)",
        pyr_path.display(),
        sizes.total as f64 / scan.input.n_vertices().max(1) as f64
    ));
    let pyr = &scan.pyramid;
    let experiments = Filter::paper_experiments();
    let mut signals = vec![("input", pyr.synthesize(&Filter::default().resolve(1.0)))];
    for (name, what, filter) in &experiments {
        let start = Instant::now();
        let out = pyr.synthesize(&filter.resolve(pyr.surface_area()));
        let path = dir.join(format!("{stem}-{name}.ply"));
        io::write_mesh(&path, &scan.output_mesh(&out))?;
        global.say(format_args!(
            "{what}: synthesised in {:.3} s, wrote {}",
            start.elapsed().as_secs_f64(),
            path.display()
        ));
        signals.push((name, out));
    }

    // Spectra: the input's, and each result re-analysed on the same hierarchy.
    let mut spectra = vec![pyr.spectrum()];
    for (_, s) in &signals[1..] {
        let p = Pyramid::analyze_signal(&scan.pm, &relaxation, s, &crate::progress::NoProgress)?;
        spectra.push(p.spectrum());
    }
    let others: Vec<(&str, &crate::pyramid::Spectrum)> = signals[1..]
        .iter()
        .map(|(n, _)| *n)
        .zip(&spectra[1..])
        .collect();
    let chart = spectra[0].chart("input", &others);
    let path = dir.join(format!("{stem}-spectrum.png"));
    io::write_atomic(&path, &chart.encode_png()?)?;
    let mut csv = String::new();
    for ((name, _), s) in signals.iter().zip(&spectra) {
        let table = s.to_csv();
        let mut lines = table.lines();
        let header = lines.next().unwrap_or_default();
        if csv.is_empty() {
            csv = format!("series,{header}\n");
        }
        for line in lines {
            csv.push_str(&format!("{name},{line}\n"));
        }
    }
    let csv_path = dir.join(format!("{stem}-spectrum.csv"));
    io::write_atomic(&csv_path, csv.as_bytes())?;
    global.say(format_args!(
        "detail spectra (input and re-analysed results): wrote {} and {}",
        path.display(),
        csv_path.display()
    ));

    // Previews with one shared camera.
    let faces = scan.pm.finest_faces();
    let options = RenderOptions {
        width: 400,
        height: 400,
        ..RenderOptions::default()
    };
    let panels: Vec<Triangles<'_>> = signals
        .iter()
        .map(|(_, s)| Triangles {
            positions: s,
            triangles: faces,
        })
        .collect();
    let all = render_panels(&panels, &options);
    let path = dir.join(format!("{stem}-preview.png"));
    io::write_atomic(&path, &all.encode_png()?)?;
    global.say(format_args!(
        "previews side by side (input | low-pass | stop-band | enhanced): wrote {}",
        path.display()
    ));
    for ((name, _), panel) in signals.iter().zip(&panels) {
        let p = dir.join(format!("{stem}-{name}.png"));
        let png = render_panels(std::slice::from_ref(panel), &options).encode_png()?;
        io::write_atomic(&p, &png)?;
        global.say(format_args!("preview of the {name}: wrote {}", p.display()));
    }
    Ok(())
}
