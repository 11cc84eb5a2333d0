//! `meshpyr view` opening a scan in stages: from the start the server answers with a first
//! picture, the stage and its progress, refuses editor calls until the pyramid is ready, shows
//! the pictures its loader offers, then serves the editor; a loader that fails ends the server
//! with its reason.

mod view_support;

use meshpyr::Pyramid;
use meshpyr_cli::view::{Picture, ViewError, ViewServer, first_picture};
use std::sync::mpsc;
use view_support::{Running, data};

const MESH: &str = "mc/mc_bunny_vox40.ply";

/// The opening picture as served: vertex count, triangles, and the picture's number.
fn served_picture(server: &Running) -> (usize, Vec<[u32; 3]>, u32) {
    let answer = server.api("GET", "/api/opening", b"");
    assert_eq!(answer.status, 200);
    let number = answer.header("X-Meshpyr-Picture").unwrap().parse().unwrap();
    let word = |k: usize| u32::from_le_bytes(answer.body[4 * k..4 * k + 4].try_into().unwrap());
    let (nv, nt) = (word(0) as usize, word(1) as usize);
    assert_eq!(answer.body.len(), 8 + 12 * nv + 12 * nt);
    let triangles = (0..nt)
        .map(|t| std::array::from_fn(|k| word(2 + 3 * nv + 3 * t + k)))
        .collect();
    (nv, triangles, number)
}

#[test]
fn an_opening_scan_shows_its_pictures_and_progress_then_the_editor() {
    let input = meshpyr::read_mesh(data(MESH)).unwrap();
    let first = first_picture(&input, 1000);
    assert!(first.what().contains("clustered"), "{}", first.what());
    let (gate, wait) = mpsc::channel::<()>();
    let scan = input.clone();
    let load = move |opening: &meshpyr_cli::view::Opening| {
        opening.stage("testing the stages");
        opening.progress(0.25);
        wait.recv().map_err(|e| e.to_string())?;
        let level = Picture::new("a second picture", &scan.positions[..3], vec![[0, 1, 2]]);
        opening.show(level);
        wait.recv().map_err(|e| e.to_string())?;
        Pyramid::build(&scan).map_err(|e| e.to_string())
    };
    let server = ViewServer::opening(first, load, 0)
        .unwrap()
        .with_name("opening.ply")
        .with_budget(2000);
    let running = Running {
        port: server.port(),
        token: server.token().to_string(),
        url: server.url(),
    };
    std::thread::spawn(move || server.run());

    let status = running.wait_status(|s| s["opening"]["done"] == 0.25);
    let opening = &status["opening"];
    assert_eq!(opening["stage"], "testing the stages");
    assert_eq!(opening["picture"], 1);
    let (nv, triangles, number) = served_picture(&running);
    assert_eq!(number, 1);
    assert_eq!(Some(triangles.len() as u64), opening["triangles"].as_u64());
    assert!(!triangles.is_empty() && triangles.len() <= 1000);
    assert!(triangles.iter().flatten().all(|&i| (i as usize) < nv));
    assert!(opening["diagonal"].as_f64().unwrap() > 0.0);

    let refused = running.api("GET", "/api/info", b"");
    assert_eq!(refused.status, 503);
    assert!(
        refused.json()["error"]
            .as_str()
            .unwrap()
            .contains("testing the stages")
    );
    assert_eq!(running.api("POST", "/api/status", b"").status, 405);

    gate.send(()).unwrap();
    running.wait_status(|s| s["opening"]["picture"] == 2);
    let (nv, triangles, number) = served_picture(&running);
    assert_eq!((nv, triangles, number), (3, vec![[0, 1, 2]], 2));

    gate.send(()).unwrap();
    running.wait_status(|s| s.get("opening").is_none());
    let info = running.api("GET", "/api/info", b"").json();
    assert_eq!(info["name"], "opening.ply");
    assert_eq!(info["vertices"], input.n_vertices());
    assert_eq!(info["display"]["budget"], 2000);
    assert_eq!(running.api("GET", "/api/opening", b"").status, 409);
}

#[test]
fn a_loader_that_fails_ends_the_server_with_its_reason() {
    let input = meshpyr::read_mesh(data(MESH)).unwrap();
    let load = |_: &meshpyr_cli::view::Opening| Err("scan.ply: cannot build it".to_string());
    let server = ViewServer::opening(first_picture(&input, 1000), load, 0).unwrap();
    match server.run() {
        Err(ViewError::Open(why)) => assert_eq!(why, "scan.ply: cannot build it"),
        other => panic!("expected the loader's failure, got {other:?}"),
    }
}

#[test]
fn a_loader_that_panics_ends_the_server_instead_of_leaving_the_page_waiting() {
    let input = meshpyr::read_mesh(data(MESH)).unwrap();
    let load = |_: &meshpyr_cli::view::Opening| -> Result<Pyramid, String> {
        panic!("a bug in the loader")
    };
    let server = ViewServer::opening(first_picture(&input, 1000), load, 0).unwrap();
    match server.run() {
        Err(ViewError::Open(why)) => assert!(why.contains("internal error"), "{why}"),
        other => panic!("expected an internal error, got {other:?}"),
    }
}
