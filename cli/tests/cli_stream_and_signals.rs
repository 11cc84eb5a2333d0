//! Memory and interruption: a small `.obj.gz` that inflates to hundreds of megabytes of
//! comment reads in bounded memory, and a command stopped by Ctrl-C or SIGTERM while writing
//! leaves no file behind (neither the output nor a hidden temporary one, nor the task files of
//! a build in blocks).
#![cfg(target_os = "linux")]

mod common;

use common::data_arg as data;
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn folder(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("meshpyr-sig-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// One triangle, then a comment of `comment_mib` MiB, gzipped while it is generated (the
/// text never exists in memory).
fn triangle_then_long_comment(path: &Path, comment_mib: usize) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut gz = flate2::write::GzEncoder::new(file, flate2::Compression::fast());
    gz.write_all(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n# ")
        .unwrap();
    let block = vec![b'x'; 1 << 20];
    for _ in 0..comment_mib {
        gz.write_all(&block).unwrap();
    }
    gz.write_all(b"\n").unwrap();
    gz.finish().unwrap().flush().unwrap();
}

/// Reading the file takes far less memory than its decompressed size: the command runs with
/// an address-space limit below the comment's size and still succeeds.
#[test]
fn a_long_comment_in_a_gzipped_obj_reads_in_bounded_memory() {
    let dir = folder("gz");
    let gz = dir.join("triangle.obj.gz");
    let comment_mib = 320;
    triangle_then_long_comment(&gz, comment_mib);
    assert!(std::fs::metadata(&gz).unwrap().len() < 2 << 20);
    let limit_bytes = 200u64 << 20;
    assert!(limit_bytes < (comment_mib as u64) << 20);
    let out = Command::new("prlimit")
        .arg(format!("--as={limit_bytes}"))
        .arg("--")
        .arg(env!("CARGO_BIN_EXE_meshpyr"))
        .args(["info", "--json"])
        .arg(&gz)
        .output()
        .expect("prlimit (util-linux) runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let info: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (info["vertices"].as_u64(), info["faces"].as_u64()),
        (Some(3), Some(1))
    );
}

/// Starts `convert` on the bunny, waits until its write is in flight (the test hook holds it
/// between writing and renaming), sends `signal` and returns the exit code.
fn interrupt_a_write(dir: &Path, signal: &str) -> Option<i32> {
    let out = dir.join("bunny.ply");
    let mut child = Command::new(env!("CARGO_BIN_EXE_meshpyr"))
        .args(["convert", &data("bunny.ply")])
        .arg(&out)
        .env(meshpyr_cli::HOLD_WRITE_ENV, "60000")
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    stderr.read_line(&mut line).unwrap();
    assert!(line.starts_with("holding "), "{line}");
    let tmp = PathBuf::from(line["holding ".len()..].trim_end());
    assert!(
        tmp.exists(),
        "the temporary file {} is in flight",
        tmp.display()
    );
    let killed = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    child.wait().unwrap().code()
}

#[test]
fn sigterm_during_a_write_leaves_no_file() {
    let dir = folder("term");
    assert_eq!(interrupt_a_write(&dir, "-TERM"), Some(143));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}

#[test]
fn ctrl_c_during_a_write_leaves_no_file() {
    let dir = folder("int");
    assert_eq!(interrupt_a_write(&dir, "-INT"), Some(130));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}

#[test]
fn sigterm_during_a_build_in_blocks_leaves_no_task_files() {
    let dir = folder("blocks");
    let tasks = dir.join("tasks");
    let mut child = Command::new(env!("CARGO_BIN_EXE_meshpyr"))
        .args(["filter", &data("bunny.ply"), "--lowpass", "1000"])
        .args(["--block-vertices", "400", "--block-files"])
        .arg(&tasks)
        .arg("-o")
        .arg(dir.join("out.ply"))
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    let in_flight = loop {
        let found = std::fs::read_dir(&tasks).ok().and_then(|mut d| d.next());
        if let Some(entry) = found {
            break entry.unwrap().path();
        }
        assert!(started.elapsed().as_secs() < 120, "no task folder appeared");
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    let killed = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    assert_eq!(child.wait().unwrap().code(), Some(143));
    assert!(!in_flight.exists(), "{} is left", in_flight.display());
    assert_eq!(std::fs::read_dir(&tasks).unwrap().count(), 0);
    assert!(!dir.join("out.ply").exists());
}
