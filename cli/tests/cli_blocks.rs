//! `--block-vertices N` and `--memory SIZE` of `build`, `filter` and `edit`: the command says
//! which path it took, forced blocks give a hierarchy every command reads, a tight memory
//! allowance takes blocks by itself, and bad values are one-line errors.

mod common;

use common::{data_arg, error_line, meshpyr, ok, path, scratch};
use std::path::Path;
use std::process::Output;

/// `meshpyr COMMAND bunny.ply -o OUT ARGS…`.
fn on_bunny(command: &str, out: &Path, args: &[&str]) -> Output {
    let bunny = data_arg("bunny.ply");
    let mut all = vec![command, &bunny, "-o", path(out)];
    all.extend_from_slice(args);
    meshpyr(&all)
}

/// `meshpyr filter bunny.ply -o OUT --lowpass 1000 ARGS…`.
fn lowpass_bunny(out: &Path, args: &[&str]) -> Output {
    let mut all = vec!["--lowpass", "1000"];
    all.extend_from_slice(args);
    on_bunny("filter", out, &all)
}

#[test]
fn filter_says_it_builds_in_one_process_when_the_scan_fits() {
    let out = scratch("blocks-fits", "out.ply");
    let err = ok(&lowpass_bunny(&out, &[]));
    assert!(
        err.contains("building the hierarchy in one process"),
        "{err}"
    );
}

#[test]
fn forced_blocks_are_said_and_their_pyr_file_filters_like_any_other() {
    let pyr = scratch("blocks-forced", "bunny.pyr");
    let err = ok(&on_bunny("build", &pyr, &["--block-vertices", "2000"]));
    assert!(
        err.contains(
            "building the hierarchy in blocks of at most 2000 vertices (--block-vertices)"
        ),
        "{err}"
    );
    let out = scratch("blocks-forced", "out.ply");
    ok(&meshpyr(&[
        "filter",
        path(&pyr),
        "-o",
        path(&out),
        "--enhance",
        "1000:10000=2",
    ]));
    let edited = scratch("blocks-forced", "edited.ply");
    let edit = [
        "--level",
        "500",
        "--move",
        "0,0,0:0,0.001,0",
        "--radius",
        "0.05",
        "--block-vertices",
        "3000",
    ];
    let err = ok(&on_bunny("edit", &edited, &edit));
    assert!(err.contains("in blocks of at most 3000 vertices"), "{err}");
}

#[test]
fn a_tight_memory_allowance_takes_the_partitioned_path_through_files_by_itself() {
    let out = scratch("blocks-memory", "out.ply");
    let err = ok(&lowpass_bunny(&out, &["--memory", "30M"]));
    assert!(err.contains("30 MB allowed"), "{err}");
    let folder = out.parent().unwrap();
    assert!(
        err.contains(&format!("through task files in {}", folder.display())),
        "{err}"
    );
    assert!(err.contains("still holds the whole mesh"), "{err}");
    // The task files are gone, and the hierarchy is the one of blocks of the size it said.
    let names: Vec<_> = std::fs::read_dir(folder)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["out.ply"]);
    let block = err.split("blocks of at most ").nth(1).unwrap();
    let block = block.split(' ').next().unwrap();
    let forced = scratch("blocks-memory-forced", "out.ply");
    ok(&lowpass_bunny(&forced, &["--block-vertices", block]));
    assert!(std::fs::read(&out).unwrap() == std::fs::read(&forced).unwrap());
    let quiet = ok(&lowpass_bunny(&out, &["--memory", "30M", "--quiet"]));
    assert!(quiet.is_empty(), "{quiet}");
}

#[test]
fn bad_block_sizes_and_memory_sizes_are_one_line_errors() {
    let out = scratch("blocks-bad", "out.ply");
    for (flag, value, needle) in [
        ("--block-vertices", "3", "at least 16"),
        ("--block-vertices", "many", "not a vertex count"),
        ("--memory", "8X", "unknown unit"),
        ("--memory", "0", "out of range"),
    ] {
        let err = error_line(&lowpass_bunny(&out, &[flag, value]));
        assert!(err.contains(needle), "{flag} {value}: {err}");
    }
}

#[test]
fn blocks_run_through_task_files_write_the_same_pyr_file_and_leave_no_files() {
    let memory = scratch("blocks-files", "memory.pyr");
    let files = scratch("blocks-files", "files.pyr");
    let folder = scratch("blocks-files", "tasks");
    ok(&on_bunny("build", &memory, &["--block-vertices", "2000"]));
    let args = ["--block-vertices", "2000", "--block-files", path(&folder)];
    let said = ok(&on_bunny("build", &files, &args));
    assert!(
        said.contains("bunny.ply: first pieces split from the file into cells"),
        "{said}"
    );
    assert!(std::fs::read(&memory).unwrap() == std::fs::read(&files).unwrap());
    assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 0);
    let quiet = [&args[..], &["-q"]].concat();
    let said = ok(&on_bunny("build", &files, &quiet));
    assert!(!said.contains("first pieces"), "{said}");
}

/// Runs each round's tasks in reverse order, as another scheduler might, and counts them.
struct CountingRunner(std::sync::atomic::AtomicUsize);

impl meshpyr::pm::blocks::TaskRunner for CountingRunner {
    fn run_round(
        &self,
        tasks: Vec<meshpyr::pm::blocks::Task>,
    ) -> Result<Vec<meshpyr::pm::blocks::TaskOutput>, meshpyr::pm::blocks::BlockFileError> {
        use std::sync::atomic::Ordering;
        self.0.fetch_add(tasks.len(), Ordering::Relaxed);
        let mut outputs = tasks
            .iter()
            .rev()
            .map(meshpyr::pm::blocks::run_task)
            .collect::<Result<Vec<_>, _>>()?;
        outputs.reverse();
        Ok(outputs)
    }
}

#[test]
fn a_command_run_in_process_with_another_runner_writes_the_same_bytes() {
    use meshpyr::pm::blocks::SharedRunner;
    use std::sync::Arc;
    let elephant = data_arg("elephant_holes.ply");
    let folder = scratch("blocks-runner", "tasks");
    let binary = scratch("blocks-runner", "binary.pyr");
    let args = ["--block-vertices", "400", "--block-files", path(&folder)];
    let mut all = vec!["build", &elephant, "-o", path(&binary)];
    all.extend_from_slice(&args);
    ok(&meshpyr(&all));
    let counting = Arc::new(CountingRunner(Default::default()));
    let in_process = scratch("blocks-runner", "in-process.pyr");
    all[3] = path(&in_process);
    let argv: Vec<std::ffi::OsString> = std::iter::once("--quiet")
        .chain(all.iter().copied())
        .map(Into::into)
        .collect();
    meshpyr_cli::run_with_block_runner(argv, SharedRunner(counting.clone())).unwrap();
    assert!(std::fs::read(&binary).unwrap() == std::fs::read(&in_process).unwrap());
    assert!(counting.0.load(std::sync::atomic::Ordering::Relaxed) > 20);
    assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 0);
    let bad = ["build", &elephant, "-o", "x.pyr", "--block-vertices", "3"].map(Into::into);
    let err = meshpyr_cli::run_with_block_runner(bad.to_vec(), SharedRunner(counting)).unwrap_err();
    let err = format!("{err:#}");
    assert!(!err.contains('\n') && err.contains("at least 16"), "{err}");
}
