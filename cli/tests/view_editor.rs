//! The in-process editor (`meshpyr_cli::view::Editor`, what the notebook widget uses) against
//! the HTTP server: the same answers for the same requests, the same caps, exact positions
//! with the bits of `Pyramid::filter`, and a snapshot page that carries the result.

mod view_support;

use meshpyr::{Filter, Pyramid};
use meshpyr_cli::view::{Editor, limits};
use serde_json::{Value, json};
use std::sync::Arc;
use view_support::{base64_decode, data, request, serve};

fn bunny_editor(budget: usize) -> (Editor, Pyramid) {
    let input = meshpyr::read_mesh(data("bunny.ply")).unwrap();
    let pyramid = Arc::new(Pyramid::build(&input).unwrap());
    let editor = Editor::new(Arc::clone(&pyramid))
        .with_name("bunny.ply")
        .with_budget(budget);
    (editor, Pyramid::build(&input).unwrap())
}

fn json_of(body: &[u8]) -> Value {
    serde_json::from_slice(body).unwrap()
}

#[test]
fn the_editor_answers_as_the_server_does() {
    let (mut editor, _) = bunny_editor(meshpyr_cli::view::DEFAULT_BUDGET);
    let server = serve("bunny.ply");
    let token = [("X-Meshpyr-Token", server.token.as_str())];
    let octaves = editor.octaves().len();
    let mut gains = vec![1.0; octaves];
    gains[octaves - 3] = 2.5;
    let state = json!({"gains": gains, "normal_only": true}).to_string();
    for (method, path, body) in [
        ("GET", "/api/info", ""),
        ("GET", "/api/faces", ""),
        ("GET", "/api/level?n=500", ""),
        ("POST", "/api/filter", state.as_str()),
        ("POST", "/api/filter", "{\"gains\": [7]}"),
        ("GET", "/api/export?format=obj", ""),
        ("GET", "/api/nothing", ""),
        ("DELETE", "/api/info", ""),
    ] {
        let ours = editor.request(method, path, body.as_bytes());
        let theirs = request(server.port, method, path, &token, body.as_bytes());
        assert_eq!(ours.status, theirs.status, "{method} {path}");
        assert_eq!(ours.body, theirs.body, "{method} {path}");
        assert_eq!(
            Some(ours.content_type.as_str()),
            theirs.header("Content-Type")
        );
    }
}

#[test]
fn the_editor_keeps_the_servers_caps() {
    let (mut editor, _) = bunny_editor(meshpyr_cli::view::DEFAULT_BUDGET);
    let long = format!("/api/info?x={}", "a".repeat(limits::URL_BYTES));
    assert_eq!(editor.request("GET", &long, b"").status, 414);
    let body = vec![b' '; limits::BODY_BYTES + 1];
    assert_eq!(editor.request("POST", "/api/filter", &body).status, 413);
    let page = editor.request("GET", "/index.html", b"");
    assert_eq!(page.status, 404, "pages are the host's to serve");
    assert!(json_of(&page.body)["error"].is_string());
}

#[test]
fn positions_are_the_bits_of_filter_and_bad_states_are_refused() {
    let (mut editor, reference) = bunny_editor(meshpyr_cli::view::DEFAULT_BUDGET);
    let octaves = editor.octaves().to_vec();
    let band = octaves.len() - 4;
    let mut gains = vec![1.0; octaves.len()];
    gains[band] = 0.0;
    let state = json!({ "gains": gains }).to_string();
    let positions = editor.positions(state.as_bytes()).unwrap();
    let (lo, hi) = octaves[band];
    let expected = reference.filter(&Filter::new().gain(lo, hi, 0.0));
    assert_eq!(positions, expected.positions);
    assert!(editor.check_state(state.as_bytes()).is_ok());
    for (bad, says) in [
        (json!({"gains": [1.0]}), "expected"),
        (json!({"gains": vec![9.0; octaves.len()]}), "outside"),
        (
            json!({"gains": vec![1.0; octaves.len()], "moves": [{"level": 1}]}),
            "bad JSON",
        ),
    ] {
        let error = editor.check_state(bad.to_string().as_bytes()).unwrap_err();
        assert!(error.contains(says), "{error}");
        assert_eq!(
            editor.positions(bad.to_string().as_bytes()).unwrap_err(),
            error
        );
    }
}

/// The inlined MESHPYR_SNAPSHOT of a saved page.
fn snapshot_of(html: &str) -> (Value, Vec<u8>, Vec<u8>) {
    let start = html.find("const MESHPYR_SNAPSHOT = {info: ").unwrap() + 32;
    let rest = &html[start..];
    let end = rest.find(", faces: '").unwrap();
    let info = json_of(&rest.as_bytes()[..end]);
    let field = |name: &str| {
        let from = rest.find(&format!("{name}: '")).unwrap() + name.len() + 3;
        let to = from + rest[from..].find('\'').unwrap();
        base64_decode(&rest[from..to])
    };
    (info, field("faces"), field("positions"))
}

#[test]
fn snapshots_carry_the_result_whole_or_at_the_shown_level() {
    let (mut editor, reference) = bunny_editor(meshpyr_cli::view::DEFAULT_BUDGET);
    let octaves = editor.octaves().to_vec();
    let mut gains = vec![1.0; octaves.len()];
    gains[octaves.len() - 2] = 2.0;
    let state = json!({ "gains": gains }).to_string();
    let html = editor.snapshot_html(state.as_bytes()).unwrap();
    assert!(!html.contains("http://") && !html.contains("https://"));
    let (info, faces, positions) = snapshot_of(&html);
    assert_eq!(info["display"]["lod"], json!(false));
    assert_eq!(faces, editor.request("GET", "/api/faces", b"").body);
    let (lo, hi) = octaves[octaves.len() - 2];
    let expected = reference.filter(&Filter::new().gain(lo, hi, 2.0));
    let f32s: Vec<u8> = expected
        .positions
        .iter()
        .flat_map(|p| p.to_array().map(|x| x as f32))
        .flat_map(f32::to_le_bytes)
        .collect();
    assert_eq!(positions, f32s);

    // Over the budget: the level the editor shows, with the exact result there.
    let (mut small, _) = bunny_editor(5_000);
    let html = small.snapshot_html(state.as_bytes()).unwrap();
    let (info, faces, positions) = snapshot_of(&html);
    let display = small.request("GET", "/api/display", b"").body;
    let shown = u32::from_le_bytes(display[..4].try_into().unwrap()) as usize;
    assert_eq!(
        info["display"],
        json!({"budget": 5000, "lod": false, "shown": shown})
    );
    assert!(shown < info["vertices"].as_u64().unwrap() as usize);
    assert_eq!(faces, display[8..]);
    assert_eq!(positions.len(), 12 * shown);
    assert!(faces.len() / 12 <= 5_000);
    let bad = json!({"gains": [1.0]}).to_string();
    assert!(small.snapshot_html(bad.as_bytes()).is_err());
}

#[test]
fn the_numbers_of_a_state_are_the_floats_sent() {
    // serde_json's default parser is off by an ulp for some decimals (this displacement's
    // x, for one); an edit sent as JSON must give the bits of the same edit made directly.
    let (mut editor, reference) = bunny_editor(meshpyr_cli::view::DEFAULT_BUDGET);
    let text = [
        "0.14850905311294338",
        "0.09608984193591164",
        "0.21668232319013336",
    ];
    let push = [
        "-0.027887909780610842",
        "0.1353055633169925",
        "-0.04076364469879845",
    ];
    let radius = "0.1602435900120939";
    let gains = vec![1.0; editor.octaves().len()];
    let state = format!(
        r#"{{"gains": {}, "moves": [{{"level": 970, "center": [{}], "displacement": [{}], "radius": {radius}}}]}}"#,
        json!(gains),
        text.join(", "),
        push.join(", ")
    );
    let vector = |t: [&str; 3]| glam::DVec3::from_array(t.map(|x| x.parse::<f64>().unwrap()));
    let handle = meshpyr::MoveHandle {
        center: vector(text),
        displacement: vector(push),
        radius: radius.parse().unwrap(),
    };
    let expected = reference.edit(970, &[handle], &Filter::new()).unwrap();
    assert_eq!(
        editor.positions(state.as_bytes()).unwrap(),
        expected.positions
    );
}
