//! The `meshpyr` command line and the browser editor behind `meshpyr view`, on the public API
//! of the [`meshpyr`] library like any other user of it.
//!
//! One subcommand per module, each with a clap `Args` struct and a `run` function; `input`
//! reads what they take (a mesh file or a `.pyr` file) as a mesh or a detail pyramid. The
//! editor's HTTP server and its page are [`view`]; `plot` draws the charts of `spectrum` and
//! `compare`.
#![warn(missing_docs)]

/// `println!` for command output that returns the write error instead of panicking, so a
/// closed pipe (`meshpyr info scan.ply | head -1`) ends the command quietly (see [`main`]).
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::stdout_line(format_args!($($arg)*))?
    };
}

mod blocks;
mod build;
mod choices;
mod compare;
mod convert;
mod demo;
mod edit;
mod extract;
mod filter;
mod info;
mod input;
mod output;
mod plot;
mod render;
mod simplify;
mod smooth;
mod spectrum;
mod subdivide;
pub mod view;
mod view_command;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
pub(crate) use output::check_mesh_output;
use std::io::IsTerminal;

/// Options every subcommand understands.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct Global {
    /// Print nothing but errors and requested output; no progress bars.
    #[arg(long, short, global = true)]
    pub(crate) quiet: bool,
}

impl Global {
    /// A progress bar on stderr that stays hidden when stderr is not a terminal or `--quiet`.
    pub(crate) fn progress(&self, message: &str) -> ProgressBar {
        let pb = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
        if self.quiet || !std::io::stderr().is_terminal() {
            pb.set_draw_target(ProgressDrawTarget::hidden());
        }
        pb.set_style(
            ProgressStyle::with_template("{msg:>12} [{bar:40}] {percent:>3}% {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        pb.set_message(message.to_string());
        pb
    }

    /// Prints a status line on stderr unless `--quiet`. Status is best effort: a closed
    /// stderr must not fail (or panic) a command whose real output is a file.
    pub(crate) fn say(&self, line: impl std::fmt::Display) {
        if !self.quiet {
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "{line}");
        }
    }
}

/// Writes one line of command output to stdout (used by `outln!`).
pub(crate) fn stdout_line(args: std::fmt::Arguments) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_fmt(args)?;
    out.write_all(b"\n")
}

/// True when the error comes from writing into a pipe whose reader has gone.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Adapts an indicatif bar to the library's [`meshpyr::progress::Progress`].
pub(crate) struct BarProgress<'a>(pub &'a ProgressBar);

impl meshpyr::progress::Progress for BarProgress<'_> {
    fn update(&self, fraction: f64) {
        self.0
            .set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
    }
}

/// meshpyr — multiresolution processing of triangle meshes and 3D scans.
#[derive(Parser, Debug)]
#[command(name = "meshpyr", version, about, long_about = None)]
pub(crate) struct Cli {
    #[command(flatten)]
    global: Global,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Counts, topology, size, and what a repair would change.
    Info(info::InfoArgs),
    /// Convert between OBJ, PLY, OFF and STL, keeping the data as it is.
    Convert(convert::ConvertArgs),
    /// Run the main job on the bundled scan and write the results to a directory.
    Demo(demo::DemoArgs),
    /// Quadric-error simplification: the progressive mesh cut at a face count, ratio or error.
    Simplify(simplify::SimplifyArgs),
    /// Subdivide a coarse mesh: cascadic mean-curvature motion (or Loop).
    Subdivide(subdivide::SubdivideArgs),
    /// Band filters on the detail pyramid: low-pass, stop-band, enhancement.
    Filter(filter::FilterArgs),
    /// Plot the detail energy per band of levels.
    Spectrum(spectrum::SpectrumArgs),
    /// Multiresolution edit: move a coarse level, resynthesise with the details.
    Edit(edit::EditArgs),
    /// Build the hierarchy and save it with the exact input as a compact .pyr file.
    Build(build::BuildArgs),
    /// Write a level of a .pyr file (the finest: the original mesh, exactly) as a mesh file.
    Extract(extract::ExtractArgs),
    /// Denoise a mesh, keeping its vertex layout: adaptive or anisotropic normal filtering
    /// with vertex fitting (Ohtake et al.), or the Taubin λ|μ and implicit MCF baselines.
    Smooth(smooth::SmoothArgs),
    /// Error of a processed mesh against a reference: E_v, E_n, Hausdorff.
    Compare(compare::CompareArgs),
    /// Interactive editor in the browser: detail equalizer, level scrubber, drag-to-edit.
    View(view_command::ViewArgs),
    /// Draw meshes side by side as a PNG, optionally coloured by a per-vertex attribute.
    Render(render::RenderArgs),
}

fn run(command: Command, global: &Global) -> anyhow::Result<()> {
    match command {
        Command::Info(a) => info::run(a, global),
        Command::Convert(a) => convert::run(a, global),
        Command::Demo(a) => demo::run(a, global),
        Command::Simplify(a) => simplify::run(a, global),
        Command::Subdivide(a) => subdivide::run(a, global),
        Command::Filter(a) => filter::run(a, global),
        Command::Spectrum(a) => spectrum::run(a, global),
        Command::Edit(a) => edit::run(a, global),
        Command::Build(a) => build::run(a, global),
        Command::Extract(a) => extract::run(a, global),
        Command::Smooth(a) => smooth::run(a, global),
        Command::Compare(a) => compare::run(a, global),
        Command::View(a) => view_command::run(a, global),
        Command::Render(a) => render::run(a, global),
    }
}

/// Runs `meshpyr ARGS` (`args`: what follows the program's name) in this process as the
/// command line would, except that the rounds of tasks of a hierarchy built in blocks through
/// task files (`build`, `filter` and `edit` with `--block-vertices N --block-files DIR`) are
/// run by `runner`: how `meshpyr.dask` runs them on a Dask cluster, with the command's very
/// options and output bytes. Help and version are printed to standard output; an error (bad
/// arguments as clap's first line) comes back to be printed as `error: {e:#}`.
pub fn run_with_block_runner(
    args: Vec<std::ffi::OsString>,
    runner: meshpyr::pm::blocks::SharedRunner,
) -> anyhow::Result<()> {
    let program = std::iter::once(std::ffi::OsString::from("meshpyr"));
    let mut cli = match Cli::try_parse_from(program.chain(args)) {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            e.print()?;
            return Ok(());
        }
        Err(e) => {
            let text = e.to_string();
            let first = text.lines().next().unwrap_or_default();
            anyhow::bail!("{}", first.trim_start_matches("error: "));
        }
    };
    match &mut cli.command {
        Command::Build(a) => a.path.runner = Some(runner),
        Command::Filter(a) => a.path.runner = Some(runner),
        Command::Edit(a) => a.path.runner = Some(runner),
        _ => {}
    }
    run(cli.command, &cli.global)
}

/// Test hook, not an interface: when set to a number of milliseconds, every output file
/// announces its temporary file on standard error and waits that long before its rename, so
/// that a test can interrupt a write reliably.
#[doc(hidden)]
pub const HOLD_WRITE_ENV: &str = "MESHPYR_TEST_HOLD_WRITE_MS";

/// Parses the command line and runs the subcommand; returns the process exit code.
pub fn main() -> std::process::ExitCode {
    remove_temporary_files_on_signals();
    if let Some(ms) = std::env::var(HOLD_WRITE_ENV)
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        meshpyr::io::hold_writes_for_tests(ms);
    }
    let cli = Cli::parse();
    match run(cli.command, &cli.global) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        // The reader of our output stopped reading (`| head`): not a failure of ours, and
        // there is nobody left to tell.
        Err(e) if is_broken_pipe(&e) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            // One line: the error and its causes joined by ": ".
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Ctrl-C, SIGTERM and SIGHUP end the process with 128 + the signal number, as the default
/// action would, but first remove the temporary files of the outputs being written (see
/// [`meshpyr::io::exit_removing_temporary_files`]); without this they stay behind, hidden.
fn remove_temporary_files_on_signals() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        // Without a handler the signals keep their default action: nothing worse than before.
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
            return;
        };
        std::thread::spawn(move || {
            if let Some(signal) = signals.forever().next() {
                meshpyr::io::exit_removing_temporary_files(128 + signal);
            }
        });
    }
}
