//! `meshpyr view IN [--port N] [--no-browser] [--budget TRIANGLES]`: the interactive editor in the browser (see the
//! library's `view` module for the page, the API and what the server exposes).

use super::Global;
use super::input::{
    build_pyramid_watched, check_memory, decode_pyr, is_pyr_file, read_input_mesh_for,
    staged_pyramid_of_pyr_file,
};
use crate::view::limits::BUDGET;
use crate::view::{EXACT_LEVELS, Loaded, Loader, Opening, Picture, ViewServer, first_picture};
use anyhow::Context;
use meshpyr::format;
use meshpyr::memory::Job;
use meshpyr::pm::ProgressiveMesh;
use meshpyr::pyramid::Staged;
use meshpyr::relax::RelaxationSpec;
use std::path::{Path, PathBuf};

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
/// so stopping it at any moment loses nothing but the page's unsaved state. The file is read
/// before serving (its errors end the command), then the page shows a first picture while the
/// pyramid is made on another thread.
pub(crate) fn run(args: ViewArgs, global: &Global) -> anyhow::Result<()> {
    let name = args
        .input
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let budget = args.budget as usize;
    let (first, load) = open_in_stages(&args.input, budget, global)?;
    let server = ViewServer::opening_loaded(first, load, args.port)?
        .with_name(&name)
        .with_budget(budget);
    let url = server.url();
    outln!("serving {url}");
    if !args.no_browser {
        open_browser(&url, global);
    }
    global.say("press Ctrl-C to stop");
    server.run()?;
    Ok(())
}

/// Reads `path` and returns the first picture of it within `budget` triangles (a `.pyr`
/// file's level read from its start, or the mesh clustered) and the loader of its pyramid,
/// which shows the hierarchy's level as soon as a mesh file's progressive mesh is built. A
/// `.pyr` file over the budget opens staged: the editor is ready on the levels its previews
/// synthesise (up to [`EXACT_LEVELS`]) while the rest of the pyramid is recorded.
fn open_in_stages(
    path: &Path,
    budget: usize,
    global: &Global,
) -> anyhow::Result<(Picture, Loader)> {
    let (path, global) = (path.to_path_buf(), global.clone());
    if is_pyr_file(&path) {
        check_memory(&path, Job::Pyramid)?;
        let file = format::PyrFile::open(&path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let level = format::read_level_within(file.bytes(), budget)
            .with_context(|| format!("cannot load {}", path.display()))?;
        if level.truncated {
            // Said now, with the decoder's words, rather than after the page has opened.
            decode_pyr(&path, file.bytes())?;
        }
        let what = format!(
            "level {} of {} vertices, read from the start of the file",
            level.level, level.finest
        );
        let first = Picture::new(what, &level.positions, level.triangles);
        let load: Loader = Box::new(move |opening: &Opening| {
            opening.stage("reading the hierarchy and its details");
            // Within the budget the page shows the finest level: nothing to stage.
            let level_of = |pm: &ProgressiveMesh| {
                if pm.finest_faces().len() > budget {
                    EXACT_LEVELS
                } else {
                    usize::MAX
                }
            };
            let staged = staged_pyramid_of_pyr_file(&path, file, &level_of, &global, opening)
                .map_err(|e| format!("{e:#}"))?;
            Ok(match staged {
                Staged::Whole(pyramid, _) => Loaded::Whole(pyramid),
                Staged::Prefix(staged) => Loaded::Staged(staged),
            })
        });
        return Ok((first, load));
    }
    let input = read_input_mesh_for(&path, Job::Pyramid)?;
    let first = first_picture(&input, budget);
    let load: Loader = Box::new(move |opening: &Opening| {
        opening.stage("building the hierarchy");
        let mut show_level = |pm: &ProgressiveMesh| {
            let level = pm.level_for_faces(budget);
            let what = format!(
                "level {level} of {} vertices of the hierarchy, at the input's positions",
                pm.n_vertices()
            );
            let positions = &pm.original_positions()[..level];
            opening.show(Picture::new(what, positions, pm.level_triangles(level)));
            opening.stage("analysing the details");
        };
        let name = path.display().to_string();
        let relaxation = RelaxationSpec::default();
        build_pyramid_watched(input, relaxation, &name, &global, opening, &mut show_level)
            .map(Loaded::Whole)
            .map_err(|e| format!("{e:#}"))
    });
    Ok((first, load))
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
