//! `meshpyr filter IN -o OUT [--lowpass N] [--stopband A:B] [--enhance A:B=G] [--gain A:B=G]
//! [--normal-only] [--relax …]`: band filters on the detail pyramid.
//!
//! Also holds the filter options and their resolution on a pyramid, which `edit` shares.

use super::Global;
use super::blocks::PathOptions;
use super::input::load_pyramid_by;
use meshpyr::pyramid::{Filter, GainBand, GainParseError, LevelSpec};
use meshpyr::relax::RelaxKind;
use meshpyr::wording::Count;
use std::path::PathBuf;
use std::time::Instant;

fn parse_band(s: &str) -> Result<(LevelSpec, LevelSpec), String> {
    GainBand::parse_band(s).map_err(|e| e.to_string())
}

/// A `--lowpass` level: like any level, but at least one vertex (a band may start at 0, a
/// low-pass may not). The option takes hyphen values so that `-1` reaches the level parser,
/// which says why it is wrong, instead of clap's advice to write `-- -1`.
fn parse_lowpass(s: &str) -> Result<LevelSpec, String> {
    let level: LevelSpec = s.parse().map_err(|e: GainParseError| e.to_string())?;
    level.for_lowpass(s).map_err(|e| e.to_string())
}

fn parse_gain_band(s: &str) -> Result<GainBand, String> {
    GainBand::parse_with_gain(s).map_err(|e| e.to_string())
}

/// The filter options shared by `filter` and `edit`.
#[derive(clap::Args, Debug, Clone, Default)]
pub(crate) struct FilterOptions {
    /// Zero the details of every level above N (a vertex count, or a feature size in model
    /// units with a `u` suffix such as 0.01u).
    #[arg(long, value_name = "N", value_parser = parse_lowpass, allow_hyphen_values = true)]
    pub(crate) lowpass: Option<LevelSpec>,
    /// Zero the details of the levels in (A, B] (repeatable).
    #[arg(long, value_name = "A:B", value_parser = parse_band)]
    pub(crate) stopband: Vec<(LevelSpec, LevelSpec)>,
    /// Multiply the details of the levels in (A, B] by G (repeatable).
    #[arg(long, value_name = "A:B=G", value_parser = parse_gain_band)]
    pub(crate) enhance: Vec<GainBand>,
    /// Generic gain band, same as --enhance (repeatable; gains of overlapping bands multiply).
    #[arg(long, value_name = "A:B=G", value_parser = parse_gain_band)]
    pub(crate) gain: Vec<GainBand>,
    /// Apply the gains to the normal component of the details only (no tangential drift).
    #[arg(long)]
    pub(crate) normal_only: bool,
}

impl FilterOptions {
    /// The filter these options describe.
    pub(crate) fn filter(&self) -> Filter {
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

/// Every warning of a filter's bands on standard error; `name` is the input, for the message.
pub(crate) fn say_band_warnings(warnings: &[String], name: &str) {
    for warning in warnings {
        eprintln!("warning: {name}: {warning}");
    }
}

/// Arguments of `meshpyr filter`.
#[derive(clap::Args, Debug)]
pub(crate) struct FilterArgs {
    /// Input mesh (.obj, .ply, .off, .stl) or .pyr file.
    pub(crate) input: PathBuf,
    /// Output mesh: the input's vertices and faces in the same order, new positions.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    #[command(flatten)]
    pub(crate) filters: FilterOptions,
    /// Relaxation operator used for the prediction (default second-difference; a .pyr input
    /// uses the one it was built with).
    #[arg(long, value_parser = crate::choices::named::<RelaxKind>())]
    pub(crate) relax: Option<RelaxKind>,
    #[command(flatten)]
    pub(crate) path: PathOptions,
}

/// Runs `meshpyr filter`.
pub(crate) fn run(args: FilterArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let filter = args.filters.filter();
    if filter.bands.is_empty() {
        anyhow::bail!(
            "no filter given: use --lowpass N, --stopband A:B, --enhance A:B=G or --gain A:B=G"
        );
    }
    let scan = load_pyramid_by(
        &args.input,
        Some(&args.output),
        args.relax,
        &args.path,
        global,
    )?;
    let start = Instant::now();
    let levels = scan.levels();
    let filtered = scan.into_filtered(&filter);
    say_band_warnings(&filtered.warnings, &args.input.display().to_string());
    global.say(format_args!(
        "synthesised {} in {:.3} s",
        Count(levels.end() - levels.start(), "level", "levels"),
        start.elapsed().as_secs_f64()
    ));
    super::output::write_mesh_output(&args.output, &filtered.mesh, &Default::default())?;
    global.say(format_args!("wrote {}", args.output.display()));
    Ok(())
}
