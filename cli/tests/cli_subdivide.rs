//! `meshpyr subdivide` end to end: output counts, determinism, error exits.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_meshpyr"))
}

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(name)
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("meshpyr-cli-subdiv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn counts(path: &Path) -> (usize, usize) {
    let m = meshpyr::io::read_mesh(path).unwrap();
    (m.n_vertices(), m.n_faces())
}

#[test]
fn subdivides_with_every_scheme_and_solver() {
    let input = data("cone20.ply");
    for (extra, faces) in [
        (vec!["--scheme", "loop"], 40 * 16),
        (vec!["--solver", "cg"], 40 * 16),
        (vec!["--solver", "jacobi", "--local-width"], 40 * 16),
        (vec!["--solver", "exact", "--width", "0.1"], 40 * 16),
        (vec!["--refine", "bisect"], 40 * 4),
    ] {
        let out = tmp("cone.ply");
        let status = bin()
            .arg("subdivide")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args(["--levels", "2", "--quiet"])
            .args(&extra)
            .status()
            .unwrap();
        assert!(status.success(), "{extra:?}");
        let (v, f) = counts(&out);
        assert_eq!(f, faces, "{extra:?}");
        // Closed genus-0 surface: V = F/2 + 2.
        assert_eq!(v, f / 2 + 2, "{extra:?}");
    }
}

#[test]
fn output_is_byte_identical_across_runs() {
    let run = |out: &Path| {
        let ok = bin()
            .args(["subdivide", "-q", "--levels", "2"])
            .arg(data("tripod.ply"))
            .arg("-o")
            .arg(out)
            .status()
            .unwrap()
            .success();
        assert!(ok);
        std::fs::read(out).unwrap()
    };
    assert_eq!(run(&tmp("a.ply")), run(&tmp("b.ply")));
}

#[test]
fn bad_input_exits_nonzero_with_one_line() {
    for args in [
        vec!["--levels", "2", "--scheme", "loop", "--refine", "bisect"],
        vec!["--levels", "30"],
        vec!["--width=-1"],
    ] {
        let out = bin()
            .arg("subdivide")
            .arg(data("cone20.ply"))
            .arg("-o")
            .arg(tmp("never.ply"))
            .args(&args)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.starts_with("error: "), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
    assert!(!tmp("never.ply").exists());
    let missing = bin()
        .args(["subdivide", "/nonexistent/x.ply", "-o"])
        .arg(tmp("x.ply"))
        .output()
        .unwrap();
    assert!(!missing.status.success());
}

#[test]
fn default_solver_is_exact_on_small_outputs() {
    // `--solver auto` (the default) must give the exact fixed point for a coarse control mesh,
    // which differs from the cascadic CG result.
    let input = data("cone20.ply");
    let run = |extra: &[&str], name: &str| {
        let out = tmp(name);
        let status = bin()
            .arg("subdivide")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args(["--levels", "2", "--quiet"])
            .args(extra)
            .status()
            .unwrap();
        assert!(status.success());
        std::fs::read(out).unwrap()
    };
    let default = run(&[], "auto.ply");
    assert_eq!(default, run(&["--solver", "exact"], "exact.ply"));
    assert_ne!(default, run(&["--solver", "cg"], "cg.ply"));
}
