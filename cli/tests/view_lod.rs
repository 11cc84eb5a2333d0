//! `meshpyr view` on a scan over its display budget (here a small scan with a small budget):
//! the shown level fits the budget, previews come at once and lie close to the exact result,
//! the exact result computed in the background equals the library's synthesis at the shown
//! vertices, and exports are exact full-resolution results.

mod view_support;

use glam::DVec3;
use meshpyr::{Filter, LevelMove, MoveHandle, Pyramid};
use serde_json::{Value, json};
use view_support::{Response, Running, bits, f32_bits, octaves_of, ply_f32s, serve_with_budget};

const MESH: &str = "mc/mc_bunny_vox40.ply";
const BUDGET: usize = 3000;

fn setup() -> (Running, Pyramid) {
    let input = meshpyr::read_mesh(view_support::data(MESH)).unwrap();
    (
        serve_with_budget(MESH, BUDGET),
        Pyramid::build(&input).unwrap(),
    )
}

fn preview(server: &Running, body: &Value) -> (Response, u64) {
    let answer = server.api("POST", "/api/preview", body.to_string().as_bytes());
    assert_eq!(
        answer.status,
        200,
        "{:?}",
        String::from_utf8_lossy(&answer.body)
    );
    let version = answer.header("X-Meshpyr-Version").unwrap().parse().unwrap();
    (answer, version)
}

fn exact(server: &Running, version: u64) -> Vec<f32> {
    server.wait_status(|s| s["exact"] == version);
    let answer = server.api("GET", &format!("/api/exact?version={version}"), b"");
    assert_eq!(answer.status, 200);
    answer.f32s()
}

fn largest_distance(a: &[f32], b: &[f32]) -> f64 {
    a.chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(p, q)| {
            let d = |k: usize| f64::from(p[k]) - f64::from(q[k]);
            (d(0) * d(0) + d(1) * d(1) + d(2) * d(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

#[test]
fn the_shown_level_fits_the_budget_and_unit_gains_preview_the_input() {
    let (server, reference) = setup();
    let info = server.api("GET", "/api/info", b"").json();
    let display = &info["display"];
    assert_eq!(display["lod"], true);
    let shown = display["shown"].as_u64().unwrap() as usize;
    let exact_level = display["exact"].as_u64().unwrap() as usize;
    assert!(reference.levels().contains(&shown) && shown < *reference.levels().end());
    assert!(exact_level <= shown);
    let answer = server.api("GET", "/api/display", b"");
    let words: Vec<u32> = answer
        .body
        .chunks_exact(4)
        .map(|w| u32::from_le_bytes(w.try_into().unwrap()))
        .collect();
    assert_eq!(words[0] as usize, shown);
    let triangles = &words[2..];
    assert_eq!(triangles.len(), 3 * words[1] as usize);
    assert!(triangles.len() / 3 <= BUDGET);
    assert_eq!(
        reference.pm.level_triangles(shown + 1).len(),
        triangles.len() / 3 + 2,
        "the next level would not fit"
    );
    assert!(triangles.iter().all(|&i| (i as usize) < shown));
    let unit = vec![1.0; octaves_of(&info).len()];
    let (answer, _) = preview(&server, &json!({ "gains": unit }));
    let positions = answer.f32s();
    assert_eq!(positions.len(), 3 * shown);
    let input: Vec<f32> = reference.pm.original_positions()[..shown]
        .iter()
        .flat_map(|p| p.to_array().map(|x| x as f32))
        .collect();
    let off = largest_distance(&positions, &input);
    assert!(off <= 1e-6 * reference.pyramid.bbox_diagonal(), "{off}");
    for part in ["synthesis", "combine", "encode"] {
        let timing = answer.header("Server-Timing").unwrap();
        assert!(timing.contains(&format!("{part};dur=")), "{timing}");
    }
}

#[test]
fn previews_lie_near_the_exact_result_which_equals_the_library_and_exports_it() {
    let (server, reference) = setup();
    let info = server.api("GET", "/api/info", b"").json();
    let bands = octaves_of(&info);
    let shown = info["display"]["shown"].as_u64().unwrap() as usize;
    let status = server
        .wait_status(|s| s["octaves"]["measured"] == s["octaves"]["total"] && s["busy"].is_null());
    assert!(status["octaves"]["total"].as_u64().unwrap() > 0, "{status}");
    let diagonal = reference.pyramid.bbox_diagonal();
    let area = reference.pyramid.surface_area();
    let last = bands.len() - 1;
    for (band, gain) in [(1, 0.0), (2, 3.0), (last - 1, 2.0), (last, 0.0)] {
        let mut gains = vec![1.0; bands.len()];
        gains[band] = gain;
        let (answer, version) = preview(&server, &json!({ "gains": gains }));
        assert_eq!(answer.header("X-Meshpyr-Preview"), Some("complete"));
        let shown_exact = exact(&server, version);
        let filter = Filter::new().gain(bands[band].0, bands[band].1, gain);
        let expected = reference.pyramid.synthesize(&filter.resolve(area));
        assert_eq!(bits(&shown_exact), f32_bits(&expected[..shown]));
        let off = largest_distance(&answer.f32s(), &shown_exact);
        println!(
            "octave {band} gain {gain}: preview within {:.4} % of the diagonal",
            100.0 * off / diagonal
        );
        assert!(off < 0.02 * diagonal, "octave {band} gain {gain}: {off}");
        let export = server.api("GET", "/api/export?format=ply", b"");
        assert_eq!(
            bits(&ply_f32s(&export.body)),
            f32_bits(&reference.filter(&filter).positions)
        );
    }
}

#[test]
fn edits_preview_and_export_the_library_s_edit() {
    let (server, reference) = setup();
    let info = server.api("GET", "/api/info", b"").json();
    let bands = octaves_of(&info);
    let shown = info["display"]["shown"].as_u64().unwrap() as usize;
    let diagonal = reference.pyramid.bbox_diagonal();
    let center = reference.pm.original_positions()[shown / 2];
    let (n0, n) = (*reference.levels().start(), *reference.levels().end());
    for level in [n0 + (shown - n0) / 4, (shown + n) / 2] {
        let handle = MoveHandle {
            center,
            displacement: DVec3::new(0.0, 0.05 * diagonal, 0.0),
            radius: 0.15 * diagonal,
        };
        let body = json!({"gains": vec![1.0; bands.len()], "moves": [{
            "level": level, "center": center.to_array(),
            "displacement": handle.displacement.to_array(), "radius": handle.radius}]});
        let (answer, version) = preview(&server, &body);
        let gains = Filter::new().resolve(reference.pyramid.surface_area());
        let expected = reference
            .pyramid
            .edit_levels(&[LevelMove { level, handle }], &gains)
            .unwrap();
        let shown_exact = exact(&server, version);
        assert_eq!(bits(&shown_exact), f32_bits(&expected[..shown]));
        let off = largest_distance(&answer.f32s(), &shown_exact);
        assert!(
            off < 0.1 * handle.displacement.length() + 0.01 * diagonal,
            "level {level}: {off}"
        );
        let export = server.api(
            "POST",
            "/api/export?format=ply",
            body.to_string().as_bytes(),
        );
        assert_eq!(
            bits(&ply_f32s(&export.body)),
            f32_bits(&reference.output_mesh(&expected).positions)
        );
    }
}

#[test]
fn the_budget_can_change_and_bad_calls_get_4xx() {
    let (server, reference) = setup();
    assert_eq!(server.api("GET", "/api/exact?version=x", b"").status, 400);
    assert_eq!(server.api("GET", "/api/exact?version=999", b"").status, 409);
    assert_eq!(server.api("PUT", "/api/preview", b"").status, 405);
    for bad in [
        json!({"triangles": 10}),
        json!({"triangles": -1}),
        json!({"budget": 5000}),
    ] {
        let answer = server.api("POST", "/api/budget", bad.to_string().as_bytes());
        assert_eq!(answer.status, 400, "{bad}");
    }
    let bigger = server
        .api("POST", "/api/budget", br#"{"triangles": 6000}"#)
        .json();
    let shown = bigger["display"]["shown"].as_u64().unwrap() as usize;
    assert!(reference.pm.level_triangles(shown).len() <= 6000);
    assert!(reference.pm.level_triangles(shown).len() > BUDGET);
    let all = reference.input.n_triangles();
    let whole = server.api(
        "POST",
        "/api/budget",
        format!("{{\"triangles\": {all}}}").as_bytes(),
    );
    assert_eq!(whole.json()["display"]["lod"], false);
    assert_eq!(server.api("GET", "/api/display", b"").status, 409);
    let unit = json!({"gains": vec![1.0; octaves_of(&whole.json()).len()]});
    assert_eq!(
        server
            .api("POST", "/api/preview", unit.to_string().as_bytes())
            .status,
        409
    );
}

/// The worker never waits for the background: a preview is answered while the background is
/// in the middle of a task, which the statuses before and after the preview prove (the same
/// task still running: busy with the same kind of work and no new result). Each try makes new
/// work, so this needs only one preview to be shorter than one background task.
#[test]
fn previews_are_answered_while_the_background_synthesises() {
    let server = serve_with_budget("bunny.ply", 20_000);
    let info = server.api("GET", "/api/info", b"").json();
    let n = octaves_of(&info).len();
    for attempt in 0..500 {
        let mut gains = vec![1.0; n];
        gains[attempt % n] = 0.5 + (attempt % 7) as f64 / 4.0;
        let before = server.api("GET", "/api/status", b"").json();
        let (answer, _) = preview(&server, &json!({ "gains": gains }));
        let after = server.api("GET", "/api/status", b"").json();
        assert_eq!(answer.status, 200);
        let same_task = !before["busy"].is_null()
            && before["busy"] == after["busy"]
            && before["exact"] == after["exact"]
            && before["octaves"]["measured"] == after["octaves"]["measured"];
        if same_task {
            return;
        }
        if before["busy"].is_null() {
            // Let the state settle so that the next try finds its exact synthesis running.
            std::thread::sleep(std::time::Duration::from_millis(160));
        }
    }
    panic!("no preview was answered while the background worked");
}
