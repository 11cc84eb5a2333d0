//! `meshpyr compare` end to end: JSON keys and values, symmetry of the Hausdorff distance,
//! human-readable output, error exits.

mod common;

use common::data;
use std::path::Path;
use std::process::{Command, Output};

fn compare(args: &[&Path], json: bool) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_meshpyr"));
    c.arg("compare").args(args);
    if json {
        c.arg("--json");
    }
    c.output().unwrap()
}

fn json(result: &str, reference: &str) -> serde_json::Value {
    let o = compare(&[&data(result), &data(reference)], true);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn json_has_every_key_and_consistent_values() {
    let v = json("fandisk_noise_n020.ply", "fandisk.ply");
    let get = |k: &str| v[k].as_f64().unwrap_or_else(|| panic!("missing {k}: {v}"));
    // serde_json's default parser may be off by an ulp.
    let same = |a: f64, b: f64| assert!((a - b).abs() <= 1e-14 * b.abs(), "{a} vs {b}");
    let diag = get("bbox_diagonal");
    let l = get("mean_edge_length");
    // fandisk per tests/data/README.md: diagonal 1.452, L 0.02066.
    assert!(
        (diag - 1.452).abs() < 1e-3 && (l - 0.02066).abs() < 1e-5,
        "{v}"
    );
    // Noise of 0.2 L along the normal: E_v is the RMS displacement (README: 0.00408).
    let e_v = get("e_v");
    assert!((e_v - 0.00408).abs() < 2e-4, "{e_v}");
    // Brute-force values of the Python reference implementation (E_v, E_n of docs/algorithms.md §5
    // with Ericson's point-triangle distance over all triangles) on the same files.
    assert!((e_v - 0.004103968731742834).abs() < 1e-12, "{e_v}");
    assert!((get("e_n") - 0.39413491163288983).abs() < 1e-10, "{v}");
    same(get("e_v_rel"), e_v / diag);
    same(get("e_v_over_l"), e_v / l);
    assert_eq!(get("e_n_rel"), get("e_n"));
    assert!(get("e_n") > 0.1 && get("e_n") < 1.0);
    let h = get("hausdorff");
    assert_eq!(
        h,
        get("hausdorff_result_to_reference").max(get("hausdorff_reference_to_result"))
    );
    same(get("hausdorff_rel"), h / diag);
    assert!(h >= e_v);
}

#[test]
fn identical_meshes_give_zero_and_hausdorff_is_symmetric() {
    let v = json("cube_om.ply", "cube_om.ply");
    assert_eq!(v["e_v"].as_f64(), Some(0.0));
    assert_eq!(v["e_n"].as_f64(), Some(0.0));
    assert!(v["hausdorff"].as_f64().unwrap() < 1e-12);
    // The CAD anchor has slivers (sin θ ≈ 5e-4) on which the closest-point test once lost
    // 1.7e-11 of the diagonal.
    let v = json("anchor.ply", "anchor.ply");
    assert!(v["hausdorff_rel"].as_f64().unwrap() < 1e-15, "{v}");
    let ab = json("cube_om_noisy.ply", "cube_om.ply");
    let ba = json("cube_om.ply", "cube_om_noisy.ply");
    assert_eq!(ab["hausdorff"], ba["hausdorff"]);
    assert_eq!(
        ab["hausdorff_result_to_reference"],
        ba["hausdorff_reference_to_result"]
    );
}

#[test]
fn json_is_byte_identical_across_thread_counts() {
    let run = |threads: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_meshpyr"))
            .env("RAYON_NUM_THREADS", threads)
            .arg("compare")
            .arg(data("fandisk_noise_i010.ply"))
            .arg(data("fandisk.ply"))
            .arg("--json")
            .output()
            .unwrap();
        assert!(o.status.success());
        o.stdout
    };
    let one = run("1");
    assert_eq!(one, run("2"));
    assert_eq!(one, run("5"));
}

#[test]
fn text_output_names_the_metrics() {
    let o = compare(&[&data("cube_om_noisy.ply"), &data("cube_om.ply")], false);
    assert!(o.status.success());
    let s = String::from_utf8_lossy(&o.stdout);
    for key in ["E_v", "E_n", "Hausdorff", "mean edge length"] {
        assert!(s.contains(key), "{s}");
    }
}

#[test]
fn bad_input_exits_nonzero_with_one_line() {
    let dir = std::env::temp_dir().join(format!("meshpyr-cli-compare-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let flat = dir.join("flat.off");
    std::fs::write(&flat, "OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n").unwrap();
    let garbage = dir.join("garbage.ply");
    std::fs::write(&garbage, "ply\nnonsense\n").unwrap();
    let missing = dir.join("missing.ply");
    let good = data("tetrahedron.ply");
    for (a, b) in [
        (&good, &flat),
        (&flat, &good),
        (&garbage, &good),
        (&good, &missing),
    ] {
        let o = compare(&[a, b], true);
        assert!(!o.status.success(), "{a:?} {b:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.starts_with("error: "), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(o.stdout.is_empty());
    }
}
