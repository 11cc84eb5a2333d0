//! `meshpyr spectrum IN -o F.png [--csv F]`: detail energy per octave of levels, plotted.

use super::Global;
use super::input::load_spectrum;
use meshpyr::io;
use meshpyr::relax::RelaxKind;
use std::path::PathBuf;

/// Arguments of `meshpyr spectrum`.
#[derive(clap::Args, Debug)]
pub(crate) struct SpectrumArgs {
    /// Input mesh (.obj, .ply, .off, .stl) or .pyr file.
    pub(crate) input: PathBuf,
    /// Output chart (PNG).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Also write the table as CSV.
    #[arg(long, value_name = "FILE")]
    pub(crate) csv: Option<PathBuf>,
    /// Relaxation operator used for the prediction (default second-difference; a .pyr input
    /// uses the one it was built with, and its stored details if they were analysed with it).
    #[arg(long, value_parser = crate::choices::named::<RelaxKind>())]
    pub(crate) relax: Option<RelaxKind>,
}

/// Runs `meshpyr spectrum`.
pub(crate) fn run(args: SpectrumArgs, global: &Global) -> anyhow::Result<()> {
    super::output::check_png_output(&args.output)?;
    if let Some(csv) = &args.csv {
        super::output::check_output_folder(csv)?;
    }
    let spectrum = load_spectrum(&args.input, args.relax, global)?;
    let png = crate::plot::spectrum_chart(&spectrum, "input", &[]).encode_png()?;
    io::write_atomic(&args.output, &png)?;
    global.say(format_args!("wrote {}", args.output.display()));
    if let Some(csv) = &args.csv {
        io::write_atomic(csv, spectrum.to_csv().as_bytes())?;
        global.say(format_args!("wrote {}", csv.display()));
    }
    Ok(())
}
