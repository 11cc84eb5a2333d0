//! The early memory check: a command whose estimated need exceeds the address-space limit
//! (`ulimit -v`) fails at once with one line saying how much it would need and how much is
//! allowed, before it reads the input's body; a run within a generous limit still works, and
//! `MESHPYR_MEMORY_CHECK=off` skips the check.
#![cfg(target_os = "linux")]

mod common;

use common::{data_arg, fails_alone_with, ok, path, scratch};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `meshpyr args` under `ulimit -v kib` (through `sh`, as a user would), with `env` set.
fn meshpyr_limited(kib: u64, args: &[&str], env: &[(&str, &str)]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {kib} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_meshpyr"))
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("sh runs")
}

/// A binary PLY whose header claims `vertices` and `triangles`, as long as that body would be
/// but sparse: no disk is used, and nothing but the header may be read.
fn sparse_ply(test: &str, name: &str, vertices: u64, triangles: u64) -> PathBuf {
    let path = scratch(test, name);
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\n\
         property float x\nproperty float y\nproperty float z\nelement face {triangles}\n\
         property list uchar int vertex_indices\nend_header\n"
    );
    let mut f = std::fs::File::create(&path).unwrap();
    std::io::Write::write_all(&mut f, header.as_bytes()).unwrap();
    f.set_len(header.len() as u64 + vertices * 12 + triangles * 13)
        .unwrap();
    path
}

/// 100M vertices and 200M triangles (3.8 GB, sparse).
fn huge_ply(test: &str) -> PathBuf {
    sparse_ply(test, "huge.ply", 100_000_000, 200_000_000)
}

/// 1 GiB, in the KiB `ulimit -v` takes.
const ONE_GB: u64 = 1 << 20;

#[test]
fn a_scan_above_ulimit_v_fails_at_once_in_one_line_saying_what_it_would_need() {
    let input = huge_ply("memory-huge");
    let name = path(&input);
    let out = |ext: &str| scratch("memory-huge", &format!("out.{ext}"));
    let commands: [(&str, Vec<&str>, &str); 6] = [
        ("filter", vec!["--lowpass", "1000"], "(the detail pyramid)"),
        ("spectrum", vec![], "(the detail pyramid)"),
        (
            "edit",
            vec!["--level", "100", "--move", "0,0,0:0,0,1", "--radius", "1"],
            "(the detail pyramid)",
        ),
        ("build", vec![], "(the detail pyramid and its .pyr file)"),
        ("simplify", vec!["--ratio", "0.1"], "(simplification)"),
        ("smooth", vec![], "(denoising)"),
    ];
    for (command, options, job) in commands {
        let ext = match command {
            "build" => "pyr",
            "spectrum" => "png",
            _ => "ply",
        };
        let output = out(ext);
        let output = path(&output);
        let mut args = vec![command, name, "-o", output];
        args.extend(options);
        let o = meshpyr_limited(ONE_GB, &args, &[]);
        let vertices = "for 100000000 vertices";
        fails_alone_with(
            &o,
            &[
                &format!("error: {name}: needs about "),
                " GB of memory ",
                vertices,
                job,
                ", 1.1 GB allowed (ulimit -v)",
                "MESHPYR_MEMORY_CHECK=off",
            ],
        );
        assert!(!Path::new(output).exists(), "{command} wrote {output}");
    }
    // `view` says it before it serves anything.
    let o = meshpyr_limited(ONE_GB, &["view", name, "--no-browser"], &[]);
    fails_alone_with(&o, &["needs about ", "1.1 GB allowed (ulimit -v)"]);
    std::fs::remove_file(&input).unwrap();
}

/// Subdivision is estimated by its output (below the library's own face limit, whose error
/// comes first above it).
#[test]
fn subdivision_is_estimated_by_its_output() {
    let input = sparse_ply("memory-subdiv", "scan.ply", 1_000_000, 2_000_000);
    let output = scratch("memory-subdiv", "out.ply");
    let o = meshpyr_limited(
        ONE_GB,
        &[
            "subdivide",
            path(&input),
            "-o",
            path(&output),
            "--levels",
            "1",
        ],
        &[],
    );
    fails_alone_with(
        &o,
        &[
            "needs about ",
            "for 4000000 vertices (subdivision, 1 level), 1.1 GB allowed (ulimit -v)",
        ],
    );
}

#[test]
fn a_pyr_file_is_estimated_from_its_header() {
    let pyr = scratch("memory-pyr", "bunny.pyr");
    ok(&common::meshpyr(&[
        "build",
        &data_arg("mc/mc_bunny_vox40.ply"),
        "-o",
        path(&pyr),
        "-q",
    ]));
    let output = scratch("memory-pyr", "out.ply");
    // Below the fixed part of any run: refused whatever the machine.
    let o = meshpyr_limited(
        200 << 10,
        &[
            "filter",
            path(&pyr),
            "-o",
            path(&output),
            "--lowpass",
            "100",
        ],
        &[],
    );
    fails_alone_with(
        &o,
        &[
            "needs about ",
            "for 5824 vertices (the detail pyramid)",
            "210 MB allowed (ulimit -v)",
        ],
    );
}

#[test]
fn a_small_scan_within_a_generous_limit_runs_as_before() {
    let output = scratch("memory-ok", "bunny.ply");
    let o = meshpyr_limited(
        8 * ONE_GB,
        &[
            "filter",
            &data_arg("bunny.ply"),
            "-o",
            path(&output),
            "--enhance",
            "1000:15000=2",
        ],
        &[],
    );
    let said = ok(&o);
    assert!(!said.contains("needs about"), "{said}");
    assert!(output.exists());
}

#[test]
fn the_check_can_be_turned_off() {
    let input = huge_ply("memory-off");
    let output = scratch("memory-off", "out.ply");
    let o = meshpyr_limited(
        ONE_GB,
        &[
            "simplify",
            path(&input),
            "-o",
            path(&output),
            "--ratio",
            "0.1",
        ],
        &[("MESHPYR_MEMORY_CHECK", "off")],
    );
    // The reader meets the limit instead, in its own words.
    let err = common::error_line(&o);
    assert!(!err.contains("needs about"), "{err}");
    assert!(err.contains("out of memory"), "{err}");
    std::fs::remove_file(&input).unwrap();
}
