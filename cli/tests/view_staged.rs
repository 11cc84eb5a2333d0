//! `meshpyr view` on a `.pyr` file opens staged: the editor answers on the pyramid of the
//! levels its previews synthesise while the whole pyramid is still being recorded, says that
//! the calls needing the whole pyramid are pending, and once it is swapped in gives the very
//! bytes of an editor opened on the whole pyramid.

mod view_support;

use meshpyr::Pyramid;
use meshpyr::format;
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::Staged;
use meshpyr_cli::view::{Loaded, ViewServer, first_picture};
use serde_json::{Value, json};
use std::sync::mpsc;
use view_support::{Running, data};

const MESH: &str = "mc/mc_bunny_vox40.ply";
const BUDGET: usize = 2000;

fn running(server: &ViewServer) -> Running {
    Running {
        port: server.port(),
        token: server.token().to_string(),
        url: server.url(),
    }
}

/// The body of a state with gain `gain` at octave `octave` (1 elsewhere).
fn state(octaves: usize, octave: usize, gain: f64) -> Vec<u8> {
    let mut gains = vec![1.0; octaves];
    gains[octave] = gain;
    serde_json::to_vec(&json!({ "gains": gains })).unwrap()
}

/// `/api/status` without what depends on the background's timing.
fn layout(status: &Value) -> &Value {
    &status["layout"]
}

#[test]
fn a_staged_pyr_file_is_edited_before_its_whole_pyramid_is_recorded_and_answers_as_a_whole_one_after()
 {
    let input = meshpyr::read_mesh(data(MESH)).unwrap();
    let (bytes, _) = Pyramid::build(&input).unwrap().to_pyr_bytes().unwrap();
    let whole = format::decode(&bytes)
        .unwrap()
        .into_pyramid(&NoProgress)
        .unwrap();
    let shown = whole.pm.level_for_faces(BUDGET);
    assert!(
        shown < whole.pm.n_vertices(),
        "the test needs a scan over the budget"
    );
    let reference = ViewServer::bind(whole, 0)
        .unwrap()
        .with_name("scan.pyr")
        .with_budget(BUDGET);
    let reference_api = running(&reference);
    std::thread::spawn(move || reference.run());

    let load = move |_: &meshpyr_cli::view::Opening| {
        let data = format::decode(&bytes).map_err(|e| e.to_string())?;
        match data.into_pyramid_staged(shown, &NoProgress) {
            Ok(Staged::Prefix(staged)) => Ok(Loaded::Staged(staged)),
            Ok(Staged::Whole(..)) => Err("the file was not staged".to_string()),
            Err(e) => Err(e.to_string()),
        }
    };
    let (release, hold) = mpsc::channel();
    let server = ViewServer::opening_loaded(first_picture(&input, BUDGET), Box::new(load), 0)
        .unwrap()
        .with_name("scan.pyr")
        .with_budget(BUDGET)
        .holding_layout(hold);
    let staged = running(&server);
    std::thread::spawn(move || server.run());

    let status = staged.wait_status(|s| s.get("opening").is_none());
    assert_eq!(layout(&status)["whole"], false, "{status}");
    assert_eq!(layout(&status)["levels"], shown);
    let info = staged.api("GET", "/api/info", b"").json();
    assert_eq!(info, reference_api.api("GET", "/api/info", b"").json());
    let octaves = info["octaves"].as_array().unwrap().len();
    let exact = info["display"]["exact"].as_u64().unwrap();
    let coarse = info["octaves"]
        .as_array()
        .unwrap()
        .iter()
        .rposition(|o| o["to"].as_u64().unwrap() <= exact)
        .expect("an octave below the exact level");
    for path in ["/api/display", "/api/faces", "/api/level?n=100"] {
        let (a, b) = (
            staged.api("GET", path, b""),
            reference_api.api("GET", path, b""),
        );
        assert_eq!((a.status, &a.body), (200, &b.body), "{path}");
    }
    // A coarse octave's preview is synthesised up to the exact level: the same bytes.
    let body = state(octaves, coarse, 2.0);
    let before = staged.api("POST", "/api/preview", &body);
    assert_eq!(before.status, 200);
    assert_eq!(before.header("X-Meshpyr-Preview"), Some("complete"));
    let expected = reference_api.api("POST", "/api/preview", &body);
    assert_eq!(before.body, expected.body);
    // What needs the whole pyramid is pending, and says so.
    let finest = format!("/api/level?n={}", info["levels"]["max"]);
    for (method, path) in [
        ("POST", "/api/filter"),
        ("POST", "/api/export?format=ply"),
        ("GET", finest.as_str()),
    ] {
        let answer = staged.api(method, path, &body);
        assert_eq!(answer.status, 503, "{path}");
        let why = answer.json()["error"].as_str().unwrap().to_string();
        assert!(why.contains("still being recorded"), "{path}: {why}");
    }
    let version: u64 = before.header("X-Meshpyr-Version").unwrap().parse().unwrap();
    assert_eq!(
        staged
            .api("GET", &format!("/api/exact?version={version}"), b"")
            .status,
        409
    );

    release.send(()).unwrap();
    // The state previewed while pending gets its exact result once the pyramid is whole.
    let status = staged.wait_status(|s| s["exact"] == version);
    assert_eq!(layout(&status)["whole"], true);
    let exact_after = staged.api("GET", &format!("/api/exact?version={version}"), b"");
    let reference_version: u64 = expected
        .header("X-Meshpyr-Version")
        .unwrap()
        .parse()
        .unwrap();
    reference_api.wait_status(|s| s["exact"] == reference_version);
    let reference_exact = reference_api.api(
        "GET",
        &format!("/api/exact?version={reference_version}"),
        b"",
    );
    assert_eq!(exact_after.body, reference_exact.body);
    for (method, path) in [
        ("POST", "/api/filter"),
        ("POST", "/api/export?format=ply"),
        ("POST", "/api/export?format=pyr"),
        ("GET", finest.as_str()),
    ] {
        let (a, b) = (
            staged.api(method, path, &body),
            reference_api.api(method, path, &body),
        );
        assert_eq!((a.status, &a.body), (200, &b.body), "{path}");
    }
    // The fine octaves, measured once whole, preview as the whole editor's.
    let measured = |s: &Value| s["octaves"]["measured"] == s["octaves"]["total"];
    staged.wait_status(measured);
    reference_api.wait_status(measured);
    let fine = state(octaves, octaves - 1, 0.5);
    let (a, b) = (
        staged.api("POST", "/api/preview", &fine),
        reference_api.api("POST", "/api/preview", &fine),
    );
    assert_eq!(a.header("X-Meshpyr-Preview"), Some("complete"));
    assert_eq!(a.body, b.body);
    assert_eq!(
        staged.api("GET", "/api/info", b"").json(),
        reference_api.api("GET", "/api/info", b"").json()
    );
}
