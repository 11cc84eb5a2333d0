//! `meshpyr view IN [--port N] [--no-browser] [--budget TRIANGLES]`: the interactive editor in the browser (see the
//! library's `view` module for the page, the API and what the server exposes).

use super::Global;
use super::input::load_pyramid;
use crate::view::ViewServer;
use crate::view::limits::BUDGET;
use std::path::PathBuf;

/// Arguments of `meshpyr view`.
#[derive(clap::Args, Debug)]
pub(crate) struct ViewArgs {
    /// Input mesh (.obj, .ply, .off, .stl) or .pyr file.
    pub(crate) input: PathBuf,
    /// Port on 127.0.0.1 (0: any free port).
    #[arg(long, default_value_t = 0)]
    pub(crate) port: u16,
    /// Print the address but do not open a browser.
    #[arg(long)]
    pub(crate) no_browser: bool,
    /// Display budget in triangles: a larger scan is shown as the finest level of its
    /// hierarchy within the budget, with the exact result computed in the background
    /// (changeable in the page).
    #[arg(long, default_value_t = crate::view::DEFAULT_BUDGET as u64,
          value_parser = clap::value_parser!(u64).range(
              *BUDGET.start() as u64..=*BUDGET.end() as u64))]
    pub(crate) budget: u64,
}

/// Runs `meshpyr view` until the process is interrupted (Ctrl-C): the server writes no file,
/// so stopping it at any moment loses nothing but the page's unsaved state.
pub(crate) fn run(args: ViewArgs, global: &Global) -> anyhow::Result<()> {
    let scan = load_pyramid(&args.input, None, global)?;
    let name = args
        .input
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let server = ViewServer::bind(scan, args.port)?
        .with_name(&name)
        .with_budget(args.budget as usize);
    let url = server.url();
    outln!("serving {url}");
    if !args.no_browser {
        open_browser(&url, global);
    }
    global.say("press Ctrl-C to stop");
    server.run();
    Ok(())
}

/// Asks the desktop to open `url`; failing that, the user has the printed address.
fn open_browser(url: &str, global: &Global) {
    let opener: &[&str] = if cfg!(target_os = "macos") {
        &["open"]
    } else if cfg!(windows) {
        &["cmd", "/C", "start", ""]
    } else {
        &["xdg-open"]
    };
    let spawned = std::process::Command::new(opener[0])
        .args(&opener[1..])
        .arg(url)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn();
    match spawned {
        // Reaped in the background so that it leaves no zombie behind.
        Ok(mut child) => drop(std::thread::spawn(move || child.wait())),
        Err(e) => global.say(format_args!(
            "could not open a browser ({}: {e}); open the address above",
            opener[0]
        )),
    }
}
