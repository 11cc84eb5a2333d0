//! The `meshpyr view` server's API over real HTTP: results equal the library's, and the
//! server answers only its own page (Host check, token, caps) and survives bad requests.

mod view_support;

use glam::DVec3;
use meshpyr::io::MeshFormat;
use meshpyr::{Filter, MoveHandle, Pyramid};
use std::sync::OnceLock;
use view_support::{Running, bits, f32_bits, octaves_of, raw, request, serve};

const MESH: &str = "mc/mc_bunny_vox40.ply";

/// One server for the whole file, and the same pyramid built again as the reference.
fn setup() -> &'static (Running, Pyramid) {
    static SETUP: OnceLock<(Running, Pyramid)> = OnceLock::new();
    SETUP.get_or_init(|| {
        let input = meshpyr::read_mesh(view_support::data(MESH)).unwrap();
        (serve(MESH), Pyramid::build(&input).unwrap())
    })
}

fn octaves(server: &Running) -> Vec<(usize, usize)> {
    octaves_of(&server.api("GET", "/api/info", b"").json())
}

#[test]
fn info_describes_the_mesh_and_octaves_tile_the_levels() {
    let (server, reference) = setup();
    let info = server.api("GET", "/api/info", b"").json();
    assert_eq!(info["vertices"], reference.input.n_vertices());
    assert_eq!(info["triangles"], reference.input.n_triangles());
    let levels = reference.levels();
    assert_eq!(info["levels"]["min"], *levels.start());
    assert_eq!(info["levels"]["max"], *levels.end());
    let bands = octaves(server);
    assert_eq!(bands[0].0, *levels.start());
    assert_eq!(bands.last().unwrap().1, *levels.end());
    assert!(bands.windows(2).all(|w| w[0].1 == w[1].0), "{bands:?}");
    for o in info["octaves"].as_array().unwrap() {
        assert!(o["feature_size"].as_f64().unwrap() > 0.0);
        assert!(o["energy"].as_f64().unwrap() >= 0.0);
    }
}

#[test]
fn filter_returns_the_bits_of_pyramid_filter_for_that_band() {
    let (server, reference) = setup();
    let bands = octaves(server);
    for (band, gain, normal_only) in [(bands.len() - 2, 2.5, false), (2, 0.0, true)] {
        let mut gains = vec![1.0; bands.len()];
        gains[band] = gain;
        let body = serde_json::json!({"gains": gains, "normal_only": normal_only});
        let answer = server.api("POST", "/api/filter", body.to_string().as_bytes());
        assert_eq!(answer.status, 200);
        assert!(answer.header("X-Meshpyr-Synthesis-Ms").is_some());
        let timing = answer
            .header("Server-Timing")
            .expect("a Server-Timing header");
        for part in ["synthesis", "reorder", "encode"] {
            assert!(timing.contains(&format!("{part};dur=")), "{timing}");
        }
        let (lo, hi) = bands[band];
        let mut filter = Filter::new().gain(lo, hi, gain);
        filter.normal_only = normal_only;
        let expected = reference.filter(&filter);
        assert_eq!(bits(&answer.f32s()), f32_bits(&expected.positions));
        assert_ne!(expected.positions, reference.input.positions);
    }
}

#[test]
fn edit_returns_the_bits_of_pyramid_edit() {
    let (server, reference) = setup();
    let n = octaves(server).len();
    let level = reference.levels().start() + 100;
    let handle = MoveHandle {
        center: reference.input.positions[17],
        displacement: DVec3::new(0.0, 0.02, 0.01),
        radius: 0.05,
    };
    let body = serde_json::json!({"gains": vec![1.0; n], "moves": [{
        "level": level, "center": handle.center.to_array(),
        "displacement": handle.displacement.to_array(), "radius": handle.radius}]});
    let answer = server.api("POST", "/api/edit", body.to_string().as_bytes());
    assert_eq!(answer.status, 200);
    let expected = reference.edit(level, &[handle], &Filter::new()).unwrap();
    assert_eq!(bits(&answer.f32s()), f32_bits(&expected.positions));
}

#[test]
fn faces_and_levels_come_as_little_endian_arrays() {
    let (server, reference) = setup();
    let faces = server.api("GET", "/api/faces", b"");
    assert_eq!(faces.body.len(), 12 * reference.input.n_triangles());
    let first: Vec<u32> = faces.body[..12]
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(first, &reference.input.face(0)[..3]);
    let n = reference.levels().start() + 50;
    let level = server.api("GET", &format!("/api/level?n={n}"), b"");
    assert_eq!(level.status, 200);
    let words: Vec<u32> = level
        .body
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let (nv, nt) = (words[0] as usize, words[1] as usize);
    assert_eq!(nv, n);
    assert_eq!(nt, reference.pm.level_triangles(n).len());
    assert_eq!(words.len(), 2 + 3 * nv + 3 * nt);
    assert!(words[2 + 3 * nv..].iter().all(|&i| (i as usize) < n));
    let expected = reference.pyramid.signal_at_level(n);
    assert_eq!(bits(&level.f32s()[2..2 + 3 * nv]), f32_bits(&expected[..n]));
}

#[test]
fn exports_are_downloads_that_load_as_meshes_and_pyramids() {
    let (server, reference) = setup();
    let bands = octaves(server);
    let mut gains = vec![1.0; bands.len()];
    gains[bands.len() - 1] = 0.0;
    let body = serde_json::json!({ "gains": gains }).to_string();
    let filtered = server.api("POST", "/api/filter", body.as_bytes()).f32s();
    let last = server.api("GET", "/api/export?format=ply", b"");
    assert_eq!(last.status, 200);
    let disposition = last.header("Content-Disposition").unwrap();
    assert!(
        disposition.starts_with("attachment; filename=\""),
        "{disposition}"
    );
    let mesh = meshpyr::io::read_mesh_bytes(&last.body, MeshFormat::Ply).unwrap();
    let loaded: Vec<f32> = mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array().map(|x| x as f32))
        .collect();
    assert_eq!(bits(&loaded), bits(&filtered));
    assert_eq!(mesh.n_faces(), reference.input.n_faces());
    let obj = server.api("POST", "/api/export?format=obj", body.as_bytes());
    let obj_mesh = meshpyr::io::read_mesh_bytes(&obj.body, MeshFormat::Obj).unwrap();
    assert_eq!(obj_mesh.n_vertices(), reference.input.n_vertices());
    let pyr = server.api("POST", "/api/export?format=pyr", body.as_bytes());
    let again = Pyramid::from_pyr_bytes(&pyr.body, &meshpyr::NoProgress).unwrap();
    assert_eq!(again.levels(), reference.levels());
    let bad = server.api("GET", "/api/export?format=exe", b"");
    assert_eq!(bad.status, 400);
}

#[test]
fn a_foreign_host_gets_403_everywhere() {
    let (server, _) = setup();
    let port = server.port.to_string();
    for host in [
        format!("evil.example:{port}"),
        format!("127.0.0.1:{}", server.port.wrapping_add(1)),
        "localhost".to_string(),
    ] {
        for path in ["/", "/app.js", "/api/info"] {
            let answer = request(
                server.port,
                "GET",
                path,
                &[("Host", &host), ("X-Meshpyr-Token", &server.token)],
                b"",
            );
            assert_eq!(answer.status, 403, "{host} {path}");
            assert!(answer.json()["error"].is_string());
        }
    }
    let ours = format!("localhost:{port}");
    let page = request(server.port, "GET", "/", &[("Host", &ours)], b"");
    assert_eq!(page.status, 200);
    assert!(String::from_utf8_lossy(&page.body).contains("meshpyr view"));
}

#[test]
fn the_api_needs_the_token_and_the_page_carries_it() {
    let (server, _) = setup();
    assert_eq!(
        request(server.port, "GET", "/api/info", &[], b"").status,
        403
    );
    let wrong = "0".repeat(server.token.len());
    let answer = request(
        server.port,
        "GET",
        "/api/info",
        &[("X-Meshpyr-Token", &wrong)],
        b"",
    );
    assert_eq!(answer.status, 403);
    let by_query = request(
        server.port,
        "GET",
        &format!("/api/info?token={}", server.token),
        &[],
        b"",
    );
    assert_eq!(by_query.status, 200);
    assert!(server.url.ends_with(&format!("/?token={}", server.token)));
    let script = request(server.port, "GET", "/app.js", &[], b"");
    assert!(String::from_utf8_lossy(&script.body).contains("X-Meshpyr-Token"));
}

#[test]
fn bad_requests_get_4xx_json_and_the_server_keeps_serving() {
    let (server, reference) = setup();
    let n = octaves(server).len();
    let big = vec![b' '; meshpyr_cli::view::limits::BODY_BYTES + 1];
    let max = reference.levels().end() + 1;
    let too_many: Vec<_> = (0..meshpyr_cli::view::limits::MAX_MOVES + 1)
        .map(|_| serde_json::json!({"level": max - 1, "center": [0,0,0], "displacement": [0,0,0], "radius": 1}))
        .collect();
    let cases: Vec<(&str, String, Vec<u8>, u16)> = vec![
        ("POST", "/api/filter".into(), big, 413),
        ("POST", "/api/filter".into(), b"{not json".to_vec(), 400),
        ("POST", "/api/filter".into(), b"\xff\xfe\x00".to_vec(), 400),
        ("POST", "/api/filter".into(), br#"{"gains": [1]}"#.to_vec(), 400),
        ("POST", "/api/filter".into(), serde_json::json!({"gains": vec![3.5; n]}).to_string().into_bytes(), 400),
        ("POST", "/api/filter".into(), serde_json::json!({"gains": vec![-1.0; n]}).to_string().into_bytes(), 400),
        ("POST", "/api/filter".into(), serde_json::json!({"gains": vec![1.0; n], "extra": 1}).to_string().into_bytes(), 400),
        ("POST", "/api/filter".into(), serde_json::json!({"gains": vec![1.0; 1_000]}).to_string().into_bytes(), 400),
        ("POST", "/api/edit".into(), serde_json::json!({"gains": vec![1.0; n], "moves": too_many}).to_string().into_bytes(), 400),
        ("POST", "/api/edit".into(), serde_json::json!({"gains": vec![1.0; n], "moves": [{"level": max, "center": [0,0,0], "displacement": [0,0,0], "radius": 1}]}).to_string().into_bytes(), 400),
        ("POST", "/api/edit".into(), serde_json::json!({"gains": vec![1.0; n], "moves": [{"level": max - 1, "center": [0,0,0], "displacement": [0,0,0], "radius": 0}]}).to_string().into_bytes(), 400),
        ("POST", "/api/edit".into(), serde_json::json!({"gains": vec![1.0; n], "moves": [{"level": max - 1, "center": [0,0,0], "displacement": [1e300,0,0], "radius": 1}]}).to_string().into_bytes(), 400),
        ("GET", "/api/level?n=abc".into(), vec![], 400),
        ("GET", format!("/api/level?n={max}"), vec![], 400),
        ("GET", "/api/level?n=99999999999999999999999".into(), vec![], 400),
        ("GET", "/api/level".into(), vec![], 400),
        ("GET", "/api/filter".into(), vec![], 405),
        ("DELETE", "/api/info".into(), vec![], 405),
        ("GET", "/api/../../etc/passwd".into(), vec![], 404),
        ("GET", "/api/nothing".into(), vec![], 404),
        ("GET", format!("/api/info?{}", "x".repeat(5000)), vec![], 414),
    ];
    for (method, path, body, status) in cases {
        let answer = server.api(method, &path, &body);
        assert_eq!(
            answer.status,
            status,
            "{method} {}",
            &path[..path.len().min(60)]
        );
        assert!(answer.json()["error"].is_string());
    }
    // Not HTTP at all; a body that ends short of its declared length; a declared length no
    // memory could hold; an honest body far over the cap; a chunked body.
    let status = |bytes: &[u8]| view_support::parse_response(&raw(server.port, bytes)).status;
    assert_eq!(status(b"\x00\x01\x02 garbage\r\n\r\n"), 400);
    let host = format!(
        "Host: 127.0.0.1:{}\r\nX-Meshpyr-Token: {}",
        server.port, server.token
    );
    let post = |rest: &str| format!("POST /api/filter HTTP/1.1\r\n{host}\r\n{rest}");
    assert_eq!(
        status(post("Content-Length: 9999\r\n\r\n{").as_bytes()),
        400
    );
    assert_eq!(
        status(post("Content-Length: 1000000000000000\r\n\r\n{").as_bytes()),
        413
    );
    assert_eq!(status(post("Content-Length: -1\r\n\r\n").as_bytes()), 400);
    let mut huge = post("Content-Length: 4000000\r\n\r\n").into_bytes();
    huge.resize(huge.len() + 4_000_000, b'[');
    assert_eq!(status(&huge), 413);
    assert_eq!(
        status(post("Transfer-Encoding: chunked\r\n\r\n1\r\n{\r\n0\r\n\r\n").as_bytes()),
        411
    );
    let mut long_head = format!("GET /api/info HTTP/1.1\r\n{host}\r\n").into_bytes();
    long_head.extend(std::iter::repeat_n(b"X-Pad: 0123456789\r\n".as_slice(), 2000).flatten());
    assert_eq!(status(&long_head), 431);
    assert_eq!(server.api("GET", "/api/info", b"").status, 200);
}

#[test]
fn a_stalled_client_does_not_hold_up_the_others() {
    let (server, _) = setup();
    let mut stalled = std::net::TcpStream::connect(("127.0.0.1", server.port)).unwrap();
    std::io::Write::write_all(&mut stalled, b"POST /api/filter HTTP/1.1\r\nContent-Le").unwrap();
    assert_eq!(server.api("GET", "/api/info", b"").status, 200);
    drop(stalled);
}

#[test]
fn stop_ends_run() {
    let input = meshpyr::read_mesh(view_support::data("tetrahedron.ply")).unwrap();
    let server = meshpyr_cli::view::ViewServer::bind(Pyramid::build(&input).unwrap(), 0).unwrap();
    let stopper = server.stopper();
    let running = std::thread::spawn(move || server.run());
    stopper.stop();
    running.join().unwrap().unwrap();
}
