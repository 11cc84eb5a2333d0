//! `meshpyr demo [--out DIR]`: the main job on the bundled scan.

use super::Global;
use super::input::build_pyramid;
use anyhow::Context;
use glam::DVec3;
use meshpyr::io::{self, MeshFormat};
use meshpyr::mesh::PolygonMesh;
use meshpyr::pyramid::{DetailPyramid, Filter, Pyramid};
use meshpyr::relax::SecondDifference;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The bundled default scan (Stanford bunny, 37.7k vertices; see `tests/data/README.md`).
pub(crate) const BUNDLED_SCAN: &[u8] = include_bytes!("../../tests/data/bunny.ply");

/// Arguments of `meshpyr demo`.
#[derive(clap::Args, Debug)]
pub(crate) struct DemoArgs {
    /// Directory for the outputs (created if missing).
    #[arg(long, default_value = "meshpyr-demo")]
    pub(crate) out: PathBuf,
}

/// Runs `meshpyr demo`.
pub(crate) fn run(args: DemoArgs, global: &Global) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let poly = io::read_mesh_bytes(BUNDLED_SCAN, MeshFormat::Ply)?;
    let info = meshpyr::mesh::MeshInfo::of(&poly)?;
    global.say(format_args!(
        "bundled scan: {} vertices, {} faces, genus {}, bbox diagonal {:.4}",
        info.vertices,
        info.faces,
        info.genus.map_or("n/a".into(), |g| g.to_string()),
        info.bbox_diagonal
    ));
    let info_path = args.out.join("bunny-info.json");
    io::write_atomic(&info_path, serde_json::to_string_pretty(&info)?.as_bytes())?;
    global.say(format_args!("wrote {}", info_path.display()));
    // The input next to the results, to open side by side in a viewer.
    let input_path = args.out.join("bunny.ply");
    io::write_mesh(&input_path, &poly)?;
    global.say(format_args!("wrote {}", input_path.display()));
    demo_filters(poly, "bunny", &args.out, global)?;
    Ok(())
}

/// The pyramid part of `meshpyr demo`: the paper's three Venus experiments (low-pass above
/// level 1000, stop-band 1000–15000, enhancement ×2 on 1000–15000) on `input`, with the
/// spectrum of each result and previews, written into `dir` with file names starting `stem`.
fn demo_filters(input: PolygonMesh, stem: &str, dir: &Path, global: &Global) -> anyhow::Result<()> {
    let relaxation = SecondDifference::default();
    let scan = build_pyramid(input, relaxation.into(), stem, global)?;
    save_hierarchy(&scan, stem, dir, global)?;
    let signals = write_filtered_meshes(&scan, stem, dir, global)?;
    write_spectra(&scan, &relaxation, &signals, stem, dir, global)?;
    write_previews(&scan, &signals, stem, dir, global)
}

/// A named vertex signal: the input's positions or a filter's result.
type Signal = (&'static str, Vec<DVec3>);

/// Saves the hierarchy: `filter`, `spectrum` and `edit` take it instead of the mesh.
fn save_hierarchy(scan: &Pyramid, stem: &str, dir: &Path, global: &Global) -> anyhow::Result<()> {
    let (bytes, sizes) = scan.to_pyr_bytes()?;
    let pyr_path = dir.join(format!("{stem}.pyr"));
    io::write_atomic(&pyr_path, &bytes)?;
    global.say(format_args!(
        "saved the hierarchy: wrote {} ({:.1} bytes/vertex)",
        pyr_path.display(),
        sizes.total as f64 / scan.input.n_vertices().max(1) as f64
    ));
    Ok(())
}

/// Runs the paper's experiments and writes each result; returns the input's signal followed by
/// the results'.
fn write_filtered_meshes(
    scan: &Pyramid,
    stem: &str,
    dir: &Path,
    global: &Global,
) -> anyhow::Result<Vec<Signal>> {
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
    Ok(signals)
}

/// Writes the spectra, as a chart and a table: the input's, and each result re-analysed on the
/// same hierarchy.
fn write_spectra(
    scan: &Pyramid,
    relaxation: &SecondDifference,
    signals: &[Signal],
    stem: &str,
    dir: &Path,
    global: &Global,
) -> anyhow::Result<()> {
    let mut spectra = vec![scan.pyramid.spectrum()];
    for (_, s) in &signals[1..] {
        let p =
            DetailPyramid::analyze_signal(&scan.pm, relaxation, s, &meshpyr::progress::NoProgress)?;
        spectra.push(p.spectrum());
    }
    let others: Vec<(&str, &meshpyr::pyramid::Spectrum)> = signals[1..]
        .iter()
        .map(|(n, _)| *n)
        .zip(&spectra[1..])
        .collect();
    let chart = crate::plot::spectrum_chart(&spectra[0], "input", &others);
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
    Ok(())
}

/// Writes the previews with one shared camera: all side by side, then each on its own.
fn write_previews(
    scan: &Pyramid,
    signals: &[Signal],
    stem: &str,
    dir: &Path,
    global: &Global,
) -> anyhow::Result<()> {
    use meshpyr::render::{Panel, RenderOptions, Triangles, render_panels, render_scene};

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
    let labelled: Vec<Panel<'_>> = signals
        .iter()
        .zip(&panels)
        .map(|(&(name, _), &mesh)| Panel {
            mesh,
            label: name,
            values: None,
            texture: None,
        })
        .collect();
    let all = render_scene(&labelled, &options);
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
