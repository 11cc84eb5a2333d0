//! `meshpyr compare --per-vertex` end to end: the written distance field keeps RESULT's data
//! and matches the library's, and the flag only adds to the output.

mod common;

use common::{data, error_line, meshpyr, ok, path};
use meshpyr::mesh::{Attribute, AttributeData};
use std::path::Path;

/// Writes the field of `result` against `reference` to `out` and returns the JSON output.
fn per_vertex(result: &Path, reference: &Path, out: &Path) -> serde_json::Value {
    let o = meshpyr(&[
        "compare",
        path(result),
        path(reference),
        "--per-vertex",
        path(out),
        "--json",
        "--quiet",
    ]);
    ok(&o);
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn per_vertex_field_is_written_with_the_results_data_and_summarised() {
    let dir = tempfile::tempdir().unwrap();
    // RESULT with an attribute of its own, which must survive.
    let mut result = meshpyr::read_mesh(data("fandisk_noise_n020.ply")).unwrap();
    let quality: Vec<f32> = (0..result.n_vertices()).map(|i| i as f32).collect();
    result.vertex_attributes.push(Attribute {
        name: "quality".into(),
        data: AttributeData::F32(quality.clone()),
    });
    let result_file = dir.path().join("result.ply");
    meshpyr::write_mesh(&result_file, &result).unwrap();
    let out = dir.path().join("field.ply");
    let v = per_vertex(&result_file, &data("fandisk.ply"), &out);

    let written = meshpyr::read_mesh(&out).unwrap();
    assert_eq!(written.positions, result.positions);
    assert_eq!(written.face_indices, result.face_indices);
    assert_eq!(
        written.vertex_attribute("quality").unwrap().data,
        AttributeData::F32(quality)
    );
    let AttributeData::F32(field) = &written.vertex_attribute("distance").unwrap().data else {
        panic!("distance is not a float column");
    };
    assert_eq!(field.len(), result.n_vertices());
    // The library's field, in the file's vertex order.
    let reference_mesh =
        meshpyr::mesh::Mesh::from_polygons(&meshpyr::read_mesh(data("fandisk.ply")).unwrap())
            .unwrap()
            .mesh;
    let reference = meshpyr::metrics::Reference::from_mesh(&reference_mesh).unwrap();
    let expected = meshpyr::metrics::vertex_distances(&result.positions, &reference);
    for (got, want) in field.iter().zip(&expected) {
        assert_eq!(*got, *want as f32);
    }

    let p = &v["per_vertex_distance"];
    let get = |k: &str| p[k].as_f64().unwrap_or_else(|| panic!("missing {k}: {v}"));
    let max = expected.iter().copied().fold(0.0, f64::max);
    // serde_json's default parser may be off by an ulp.
    assert!(
        (get("max") - max).abs() <= 1e-15 * max,
        "{} vs {max}",
        get("max")
    );
    assert!(get("p50") <= get("p90") && get("p90") <= get("p99") && get("p99") <= get("max"));
    // The vertices' largest distance is the vertex part of the sampled Hausdorff distance.
    assert!(max <= v["hausdorff_result_to_reference"].as_f64().unwrap());
    assert!(get("p50") > 0.0);
}

#[test]
fn per_vertex_needs_a_ply_and_only_adds_to_the_output() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (data("fandisk_noise_n020.ply"), data("fandisk.ply"));
    let obj = dir.path().join("field.obj");
    let err = error_line(&meshpyr(&[
        "compare",
        path(&a),
        path(&b),
        "--per-vertex",
        path(&obj),
    ]));
    assert!(err.contains("field.obj") && err.contains(".ply"), "{err}");
    assert!(!obj.exists());
    let o = meshpyr(&["compare", path(&a), path(&b), "--json"]);
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v.get("per_vertex_distance").is_none(), "{v}");
    // With the flag, the same keys in the same order, then the percentiles.
    let field = dir.path().join("field.ply");
    let with = meshpyr(&[
        "compare",
        path(&a),
        path(&b),
        "--json",
        "--per-vertex",
        path(&field),
    ]);
    ok(&with);
    let (plain, with) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&with.stdout),
    );
    let prefix = plain.trim_end().strip_suffix('}').unwrap();
    assert!(
        with.starts_with(&format!("{prefix},\"per_vertex_distance\":{{")),
        "{with}"
    );
    // Text output gains one line with the percentiles.
    let o = meshpyr(&["compare", path(&a), path(&b), "--per-vertex", path(&field)]);
    ok(&o);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.lines()
            .any(|l| l.contains("per vertex") && l.contains("p99")),
        "{text}"
    );
}
