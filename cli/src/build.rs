//! `meshpyr build IN -o OUT.pyr [--relax …] [--no-details]`: build the progressive mesh and
//! its detail pyramid and save them with the exact input as a `.pyr` file (see
//! `formats/pyr.md`).

use super::blocks::PathOptions;
use super::input::read_input_mesh_for;
use super::{BarProgress, Global};
use anyhow::Context;
use meshpyr::format;
use meshpyr::io;
use meshpyr::memory::Job;
use meshpyr::pm::{PmOptions, ProgressiveMesh};
use meshpyr::pyramid::{PyrContent, Pyramid, PyramidOptions};
use meshpyr::relax::RelaxKind;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `meshpyr build`.
#[derive(clap::Args, Debug)]
pub(crate) struct BuildArgs {
    /// Input mesh (.obj, .ply, .off, .stl, or a .pyr file: its stored input mesh).
    pub(crate) input: PathBuf,
    /// Output `.pyr` file.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Relaxation operator the pyramid is analysed with (recorded in the file; `filter`,
    /// `spectrum` and `edit` use it).
    #[arg(long, value_parser = crate::choices::named::<RelaxKind>(), default_value = RelaxKind::default().spec().name())]
    pub(crate) relax: RelaxKind,
    /// Leave the details out: a smaller file (about 60 % less on scans), whose readers run
    /// the detail analysis every time they open it.
    #[arg(long)]
    pub(crate) no_details: bool,
    /// For a textured input: weight of the texture-coordinate error against the geometric
    /// error, as for `simplify` (recorded in the file; docs/seams.md).
    #[arg(long, value_name = "W", default_value_t = PmOptions::default().uv_weight)]
    pub(crate) uv_weight: f64,
    #[command(flatten)]
    pub(crate) path: PathOptions,
}

/// Runs `meshpyr build`.
pub(crate) fn run(args: BuildArgs, global: &Global) -> anyhow::Result<()> {
    super::output::check_output_folder(&args.output)?;
    // Without details: the progressive mesh only, a pyramid's worth of memory at most.
    let job = if args.no_details {
        Job::Pyramid
    } else {
        Job::SavePyramid
    };
    let input = read_input_mesh_for(&args.input, job)?;
    let options = PyramidOptions {
        relaxation: args.relax.spec(),
        pm: PmOptions {
            uv_weight: args.uv_weight,
            ..(args.path).pm_options(&args.input, Some(&args.output), job, &input, global)?
        },
    };
    let n_input = input.n_vertices();
    let start = Instant::now();
    let (encoded, pm) = if args.no_details {
        let bar = global.progress("build");
        let (pm, _) = ProgressiveMesh::from_polygons(&input, &options.pm, &BarProgress(&bar))
            .with_context(|| {
                format!(
                    "cannot build the progressive mesh of {}",
                    args.input.display()
                )
            })?;
        bar.finish_and_clear();
        let encoded = format::encode_sections(&input, &pm, &options, None)
            .with_context(|| format!("cannot encode {}", args.input.display()))?;
        (encoded, pm)
    } else {
        let bar = global.progress("build");
        let pyramid = Pyramid::build_with(input, &options, &BarProgress(&bar))
            .with_context(|| format!("cannot build the pyramid of {}", args.input.display()))?;
        bar.finish_and_clear();
        pyramid
            .into_encoded(PyrContent::WithDetails)
            .with_context(|| format!("cannot encode {}", args.input.display()))?
    };
    let took = start.elapsed().as_secs_f64();
    super::input::say_first_pieces(&args.input.display().to_string(), &pm, global);
    io::write_atomic_with(&args.output, |w| encoded.write_to(w))?;
    let sizes = encoded.sizes;
    let n = n_input.max(1) as f64;
    global.say(format_args!(
        "wrote {}: {} bytes for {} vertices, levels {}..={} ({} and encoded in {took:.1} s){}",
        args.output.display(),
        sizes.total,
        n_input,
        pm.n_base_vertices(),
        pm.n_vertices(),
        if args.no_details {
            "hierarchy built"
        } else {
            "hierarchy and details built"
        },
        super::input::extra_vertices_note(n_input, pm.n_vertices()),
    ));
    global.say(format_args!(
        "  bytes/vertex: whole file {:.2}, PM connectivity {:.2}, split errors {:.2}, positions {:.2}, input order+polygons+attributes {:.2}{}",
        sizes.total as f64 / n,
        sizes.pm_connectivity as f64 / n,
        sizes.split_errors as f64 / n,
        sizes.positions as f64 / n,
        sizes.trailing as f64 / n,
        if args.no_details {
            String::new()
        } else {
            format!(", details {:.2}", sizes.details as f64 / n)
        }
    ));
    global.say(format_args!("  {}", pm.describe_base()));
    Ok(())
}
