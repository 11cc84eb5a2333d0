//! `meshpyr info`, `convert` and `demo` as a user runs them.

mod common;

use common::{data_arg as data, meshpyr, scratch};
use std::process::Command;

fn info_json(path: &str) -> serde_json::Value {
    let out = meshpyr(&["info", path, "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("info --json prints one JSON object")
}

#[test]
fn info_json_describes_the_bundled_scan() {
    let v = info_json(&data("bunny.ply"));
    assert_eq!(v["vertices"], 37706);
    assert_eq!(v["faces"], 75408);
    assert_eq!(v["edges"], 113112);
    assert_eq!(v["boundary_loops"], 0);
    assert_eq!(v["components"], 1);
    assert_eq!(v["euler_characteristic"], 2);
    assert_eq!(v["genus"], 0);
    assert_eq!(v["manifold"], true);
    let diag = v["bbox_diagonal"].as_f64().unwrap();
    assert!((diag - 1.602).abs() < 1e-3, "{diag}");
    let mel = v["mean_edge_length"].as_f64().unwrap();
    assert!((mel - 0.008106).abs() < 1e-5, "{mel}");
    assert_eq!(v["repairs"]["split_vertices"], 0);
}

#[test]
fn info_text_mentions_counts() {
    let out = meshpyr(&["info", &data("bunny.ply")]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("vertices 37706"), "{text}");
    assert!(text.contains("repairs: none needed"), "{text}");
}

#[test]
fn convert_keeps_counts_in_every_format() {
    let reference = info_json(&data("bunny.ply"));
    for ext in ["obj", "off", "stl", "ply"] {
        let out_path = scratch("cli-info", &format!("bunny.{ext}"));
        let out = meshpyr(&["convert", &data("bunny.ply"), out_path.to_str().unwrap()]);
        assert!(
            out.status.success(),
            "{ext}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v = info_json(out_path.to_str().unwrap());
        for key in [
            "vertices",
            "faces",
            "edges",
            "genus",
            "boundary_loops",
            "components",
        ] {
            assert_eq!(v[key], reference[key], "{ext}: {key}");
        }
    }
}

#[test]
fn errors_are_one_line_and_non_zero() {
    let missing = scratch("cli-info", "does-not-exist.ply");
    let bad_ext = scratch("cli-info", "mesh.xyz");
    std::fs::write(&bad_ext, b"1 2 3").unwrap();
    let truncated = scratch("cli-info", "truncated.ply");
    let bunny = std::fs::read(data("bunny.ply")).unwrap();
    std::fs::write(&truncated, &bunny[..bunny.len() / 2]).unwrap();
    for path in [&missing, &bad_ext, &truncated] {
        let out = meshpyr(&["info", path.to_str().unwrap()]);
        assert!(!out.status.success(), "{} was accepted", path.display());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.starts_with("error: "), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
}

#[test]
fn output_errors_name_the_output_once_and_come_before_the_work() {
    let input = data("joint.ply");
    // A missing directory: the message names the requested file, not a temporary one, and
    // says the reason once, before any work.
    let target = scratch("cli-info", "no-such-dir").join("out.ply");
    let out = meshpyr(&[
        "simplify",
        input.as_str(),
        "-o",
        target.to_str().unwrap(),
        "--ratio",
        "0.5",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains(target.to_str().unwrap()), "{err}");
    assert!(!err.contains(".tmp"), "{err}");
    assert!(err.starts_with("error: cannot write"), "{err}");
    assert_eq!(err.matches("does not exist").count(), 1, "{err}");
    // An unknown output extension fails before the pyramid is built (nothing else printed).
    let out = meshpyr(&[
        "filter",
        input.as_str(),
        "-o",
        scratch("cli-info", "out.xyz").to_str().unwrap(),
        "--lowpass",
        "50",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("unknown mesh format"), "{err}");
}

#[test]
fn failed_convert_leaves_existing_output_alone() {
    let target = scratch("cli-info", "keep-me.ply");
    std::fs::write(&target, b"precious").unwrap();
    let truncated = scratch("cli-info", "half.ply");
    let bunny = std::fs::read(data("bunny.ply")).unwrap();
    std::fs::write(&truncated, &bunny[..1000]).unwrap();
    let out = meshpyr(&[
        "convert",
        truncated.to_str().unwrap(),
        target.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert_eq!(std::fs::read(&target).unwrap(), b"precious");
}

#[test]
fn demo_writes_its_outputs() {
    let dir = scratch("cli-info", "demo");
    let out = meshpyr(&["demo", "--out", dir.to_str().unwrap(), "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "--quiet printed {:?}",
        String::from_utf8_lossy(&out.stderr)
    );
    let entries = std::fs::read_dir(&dir).unwrap().count();
    assert!(entries >= 2, "demo wrote {entries} files");
}

#[test]
fn gzip_meshes_convert_and_read_by_extension() {
    let gz = scratch("cli-info", "bunny.ply.gz");
    let out = meshpyr(&["convert", &data("bunny.ply"), gz.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(&std::fs::read(&gz).unwrap()[..2], &[0x1f, 0x8b]);
    assert_eq!(
        info_json(gz.to_str().unwrap()),
        info_json(&data("bunny.ply"))
    );
}

#[test]
fn a_reader_that_stops_early_is_not_an_error() {
    // `meshpyr info scan.ply | head -1`: the pipe closes before the output is written.
    let mut child = Command::new(env!("CARGO_BIN_EXE_meshpyr"))
        .args(["info", &data("bunny.ply")])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
