//! `meshpyr view` in a real headless Chromium, driven over WebDriver (plain HTTP/JSON, spoken
//! by the small client in `view_support`): the page draws the bunny, the equalizer returns
//! exactly what `Pyramid::filter` gives, the scrubber shows a coarser level, a drag edit moves
//! the surface near the pick only, export gives a mesh that loads, and the page needs its token.
//!
//! Needs `chromium` and `chromedriver` on PATH (Debian: `chromium`, `chromium-driver`; .ci/run
//! installs them). Without them the test prints SKIP and passes, unless
//! `MESHPYR_REQUIRE_BROWSER=1`, which CI sets.

mod view_support;

use meshpyr::io::MeshFormat;
use meshpyr::{Filter, Pyramid};
use serde_json::{Value, json};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use view_support::{Running, base64_decode, request, serve};

const ELEMENT: &str = "element-6066-11e4-a52e-4f735466cecf";

fn on_path(names: &[&str]) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| names.iter().map(move |n| dir.join(n)))
        .find(|p| p.is_file())
}

/// A chromedriver process with one Chromium session, both ended on drop.
struct Driver {
    port: u16,
    session: String,
    child: Child,
    _profile: tempfile::TempDir,
}

impl Driver {
    /// Starts chromedriver and a headless Chromium, or says why not (missing binaries).
    fn start() -> Result<Driver, String> {
        let chromium = on_path(&["chromium", "chromium-browser"])
            .ok_or("no chromium on PATH (Debian package `chromium`)")?;
        let chromedriver = on_path(&["chromedriver"])
            .ok_or("no chromedriver on PATH (Debian package `chromium-driver`)")?;
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .and_then(|l| l.local_addr())
            .map_err(|e| e.to_string())?
            .port();
        let child = Command::new(chromedriver)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| format!("cannot start chromedriver: {e}"))?;
        let profile = tempfile::tempdir().map_err(|e| e.to_string())?;
        let mut driver = Driver {
            port,
            session: String::new(),
            child,
            _profile: profile,
        };
        driver.wait_ready()?;
        let args = [
            "--headless=new",
            "--no-sandbox",
            "--disable-gpu",
            "--enable-unsafe-swiftshader",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--window-size=1280,800",
            &format!("--user-data-dir={}", driver._profile.path().display()),
        ];
        let caps = json!({"capabilities": {"alwaysMatch": {"browserName": "chrome",
            "goog:chromeOptions": {"binary": chromium, "args": args}}}});
        let created = driver.call("POST", "/session", &caps);
        driver.session = created["sessionId"]
            .as_str()
            .ok_or_else(|| format!("no session: {created}"))?
            .to_string();
        driver.call_session("POST", "/timeouts", &json!({"script": 120_000}));
        Ok(driver)
    }

    fn wait_ready(&self) -> Result<(), String> {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(30) {
            let probe = format!(
                "GET /status HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nConnection: close\r\n\r\n",
                self.port
            );
            let up = std::net::TcpStream::connect(("127.0.0.1", self.port)).is_ok()
                && String::from_utf8_lossy(&view_support::exchange(
                    self.port,
                    probe.as_bytes(),
                    Duration::from_secs(5),
                    false,
                ))
                .contains("\"ready\":true");
            if up {
                return Ok(());
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        Err("chromedriver did not start".into())
    }

    /// A WebDriver command; returns its `value`.
    fn call(&self, method: &str, path: &str, body: &Value) -> Value {
        let body = if body.is_null() {
            Vec::new()
        } else {
            body.to_string().into_bytes()
        };
        let headers = [("Content-Type", "application/json")];
        let answer = request(self.port, method, path, &headers, &body);
        let value = answer.json()["value"].clone();
        assert!(answer.status == 200, "WebDriver {method} {path}: {}", value);
        value
    }

    fn call_session(&self, method: &str, path: &str, body: &Value) -> Value {
        self.call(method, &format!("/session/{}{path}", self.session), body)
    }

    fn navigate(&self, url: &str) {
        self.call_session("POST", "/url", &json!({ "url": url }));
    }

    /// Runs `body` as a function in the page and returns its result.
    fn script(&self, body: &str) -> Value {
        self.call_session(
            "POST",
            "/execute/sync",
            &json!({"script": body, "args": []}),
        )
    }

    /// Runs `body`, which calls `done(result)` when finished.
    fn async_script(&self, body: &str) -> Value {
        let script = format!("const done = arguments[arguments.length - 1]; {body}");
        self.call_session(
            "POST",
            "/execute/async",
            &json!({"script": script, "args": []}),
        )
    }

    /// Polls `condition` (a JS expression) until it holds.
    fn wait_for(&self, condition: &str) {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(120) {
            if self.script(&format!("return !!({condition});")) == json!(true) {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let error = self.script("return document.getElementById('error').textContent;");
        panic!("timed out waiting for {condition} (page error: {error})");
    }

    fn canvas(&self) -> String {
        let found = self.call_session(
            "POST",
            "/element",
            &json!({"using": "css selector", "value": "#canvas"}),
        );
        found[ELEMENT].as_str().unwrap().to_string()
    }

    /// The canvas as RGB pixels.
    fn canvas_pixels(&self) -> Vec<u8> {
        let id = self.canvas();
        let shot = self.call_session("GET", &format!("/element/{id}/screenshot"), &Value::Null);
        decode_png(&base64_decode(shot.as_str().unwrap())).1
    }

    fn window_png(&self) -> Vec<u8> {
        let shot = self.call_session("GET", "/screenshot", &Value::Null);
        base64_decode(shot.as_str().unwrap())
    }

    fn positions(&self) -> Vec<f32> {
        let v = self.script("return Array.from(window.meshpyr.positions);");
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect()
    }

    /// Sets range input `selector` to `value` as a user would and waits for the page to settle.
    fn slide(&self, selector: &str, value: f64) {
        self.script(&format!(
            "const s = document.querySelector({}); s.value = {value};
             s.dispatchEvent(new Event('input', {{bubbles: true}}));",
            json!(selector)
        ));
        self.wait_for("window.meshpyr.idle()");
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        if !self.session.is_empty() {
            let path = format!("/session/{}", self.session);
            let _ = request(self.port, "DELETE", &path, &[], b"");
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn decode_png(bytes: &[u8]) -> ((u32, u32), Vec<u8>) {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    let rgb = match info.color_type {
        png::ColorType::Rgb => buf,
        png::ColorType::Rgba => buf
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect(),
        other => panic!("unexpected screenshot colours {other:?}"),
    };
    ((info.width, info.height), rgb)
}

/// Share of pixels that differ by more than a little in some channel.
fn changed_share(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len());
    let changed = a
        .chunks_exact(3)
        .zip(b.chunks_exact(3))
        .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > 8))
        .count();
    changed as f64 / (a.len() / 3) as f64
}

fn f32_bits(positions: &[glam::DVec3]) -> Vec<u32> {
    positions
        .iter()
        .flat_map(|p| p.to_array().map(|x| (x as f32).to_bits()))
        .collect()
}

fn bits(values: &[f32]) -> Vec<u32> {
    values.iter().map(|x| x.to_bits()).collect()
}

/// The driver, or `None` (after printing why) when the browser is missing and not required.
fn driver_or_skip(test: &str) -> Option<Driver> {
    match Driver::start() {
        Ok(d) => Some(d),
        Err(why) if std::env::var("MESHPYR_REQUIRE_BROWSER").as_deref() != Ok("1") => {
            println!("SKIP {test}: {why} (set MESHPYR_REQUIRE_BROWSER=1 to fail instead)");
            None
        }
        Err(why) => panic!("{test}: {why}, and MESHPYR_REQUIRE_BROWSER=1"),
    }
}

#[test]
fn the_editor_works_in_a_headless_browser() {
    let Some(driver) = driver_or_skip("the_editor_works_in_a_headless_browser") else {
        return;
    };
    let server = serve("bunny.ply");
    let input = meshpyr::read_mesh(view_support::data("bunny.ply")).unwrap();
    let reference = Pyramid::build(&input).unwrap();
    driver.navigate(&server.url);
    driver.wait_for("window.meshpyr && window.meshpyr.ready && window.meshpyr.idle()");
    let original = page_draws_the_mesh(&driver);
    let filtered = slider_gives_the_bits_of_filter(&driver, &reference, &original);
    scrubber_shows_a_coarser_level(&driver, &reference, &filtered);
    let edited = drag_moves_the_surface_near_the_pick(&driver);
    export_loads_as_a_mesh(&driver, &edited);
    if let Some(path) = std::env::var_os("MESHPYR_VIEW_SCREENSHOT") {
        take_screenshot(&driver, &PathBuf::from(path));
    }
    page_needs_the_token(&driver, &server);
}

fn page_draws_the_mesh(driver: &Driver) -> Vec<u8> {
    let pixels = driver.canvas_pixels();
    let background = [18u8, 20, 26];
    let drawn = pixels
        .chunks_exact(3)
        .filter(|p| p.iter().zip(background).any(|(x, y)| x.abs_diff(y) > 30))
        .count();
    let share = drawn as f64 / (pixels.len() / 3) as f64;
    assert!(
        share > 0.03,
        "only {:.2}% of the canvas is drawn",
        100.0 * share
    );
    pixels
}

fn slider_gives_the_bits_of_filter(driver: &Driver, reference: &Pyramid, before: &[u8]) -> Vec<u8> {
    let octaves = reference.pyramid.levels_of_octaves();
    let band = octaves.len() - 3;
    let updates = driver.script("return window.meshpyr.updates;");
    driver.slide(&format!("#bands input[data-band='{band}']"), 3.0);
    assert_ne!(driver.script("return window.meshpyr.updates;"), updates);
    let (lo, hi) = octaves[band];
    let expected = reference.filter(&Filter::new().gain(lo, hi, 3.0));
    assert_eq!(bits(&driver.positions()), f32_bits(&expected.positions));
    let after = driver.canvas_pixels();
    let share = changed_share(before, &after);
    assert!(share > 0.003, "the picture hardly changed: {share}");
    after
}

fn scrubber_shows_a_coarser_level(driver: &Driver, reference: &Pyramid, before: &[u8]) {
    driver.slide("#level", 300.0);
    let shown = driver.script("return window.meshpyr.shownLevel;");
    let shown = shown.as_u64().expect("a level is shown") as usize;
    assert!(reference.levels().contains(&shown) && shown < *reference.levels().end());
    let share = changed_share(before, &driver.canvas_pixels());
    assert!(share > 0.01, "the coarse level looks the same: {share}");
    driver.slide("#level", 1000.0);
    assert_eq!(
        driver.script("return window.meshpyr.shownLevel;"),
        Value::Null
    );
}

/// Resets the equalizer, drags upwards from the canvas centre in edit mode, and checks where
/// the surface moved; returns the edited positions.
fn drag_moves_the_surface_near_the_pick(driver: &Driver) -> Vec<f32> {
    driver.script("document.querySelector(\"[data-preset='reset']\").click();");
    driver.wait_for("window.meshpyr.idle() && window.meshpyr.gains.every((g) => g === 1)");
    let before = driver.positions();
    driver.script("document.getElementById('edit-mode').click();");
    let canvas = driver.canvas();
    let mouse = |actions: Value| {
        json!({"actions": [{"type": "pointer", "id": "mouse",
            "parameters": {"pointerType": "mouse"}, "actions": actions}]})
    };
    driver.call_session(
        "POST",
        "/actions",
        &mouse(json!([
            {"type": "pointerMove", "duration": 0, "origin": {ELEMENT: canvas}, "x": 0, "y": 0},
            {"type": "pointerDown", "button": 0},
            {"type": "pointerMove", "duration": 400, "origin": "pointer", "x": 0, "y": -60},
            {"type": "pointerUp", "button": 0},
        ])),
    );
    driver.wait_for("window.meshpyr.moves.length === 1 && window.meshpyr.idle()");
    let after = driver.positions();
    let m = driver.script("return window.meshpyr.moves[0];");
    let v = |k: &str| {
        glam::DVec3::from_slice(&serde_json::from_value::<Vec<f64>>(m[k].clone()).unwrap())
    };
    let (center, push) = (v("center"), v("displacement"));
    let radius = m["radius"].as_f64().unwrap();
    assert!(push.length() > 0.0);
    let moved: Vec<(f64, f64)> = before
        .chunks_exact(3)
        .zip(after.chunks_exact(3))
        .map(|(a, b)| {
            let a = glam::DVec3::new(a[0].into(), a[1].into(), a[2].into());
            let b = glam::DVec3::new(b[0].into(), b[1].into(), b[2].into());
            ((a - center).length(), (b - a).length())
        })
        .collect();
    let (near_distance, most) = moved
        .iter()
        .copied()
        .fold((0.0, 0.0), |best, x| if x.1 > best.1 { x } else { best });
    assert!(
        most > 0.5 * push.length(),
        "moved {most}, pushed {}",
        push.length()
    );
    assert!(
        near_distance < radius,
        "largest move {near_distance} from the pick, radius {radius}"
    );
    let far = moved
        .iter()
        .filter(|(d, _)| *d > 2.0 * radius)
        .map(|m| m.1)
        .fold(0.0, f64::max);
    assert!(
        far < 0.02 * most,
        "vertices beyond two radii moved {far} (peak {most})"
    );
    println!(
        "drag edit: peak move {most:.4} at {near_distance:.4} from the pick, at most {far:.2e} beyond two radii ({radius:.4})"
    );
    after
}

fn export_loads_as_a_mesh(driver: &Driver, shown: &[f32]) {
    let result = driver.async_script(
        "window.meshpyr.exportBytes('ply').then(({bytes, name}) => {
            let s = '';
            for (let i = 0; i < bytes.length; i += 32768) {
                s += String.fromCharCode.apply(null, bytes.subarray(i, i + 32768));
            }
            done({name, data: btoa(s)});
        }).catch((e) => done({error: String(e)}));",
    );
    assert!(result["error"].is_null(), "{}", result["error"]);
    assert_eq!(result["name"], "bunny-view.ply");
    let bytes = base64_decode(result["data"].as_str().unwrap());
    let mesh = meshpyr::io::read_mesh_bytes(&bytes, MeshFormat::Ply).unwrap();
    let loaded: Vec<f32> = mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array().map(|x| x as f32))
        .collect();
    assert_eq!(bits(&loaded), bits(shown));
}

fn take_screenshot(driver: &Driver, path: &std::path::Path) {
    driver.script("document.getElementById('edit-mode').click();");
    driver.script("document.querySelector(\"[data-preset='enhance']\").click();");
    driver.wait_for("window.meshpyr.idle() && window.meshpyr.gains.some((g) => g === 2)");
    std::fs::write(path, driver.window_png()).unwrap();
}

fn page_needs_the_token(driver: &Driver, server: &Running) {
    driver.navigate(&format!("http://127.0.0.1:{}/", server.port));
    driver.wait_for("document.getElementById('error').textContent.includes('token')");
    let by_name = format!("http://localhost:{}/?token={}", server.port, server.token);
    driver.navigate(&by_name);
    driver.wait_for("window.meshpyr && window.meshpyr.ready");
}

/// End-to-end latency of equalizer moves on a large scan: `MESHPYR_VIEW_LATENCY_MESH=scan.ply
/// cargo test --release --test view_browser -- --ignored --nocapture` (docs/performance.md).
#[test]
#[ignore = "needs a large scan named by MESHPYR_VIEW_LATENCY_MESH; run by hand"]
fn equalizer_latency_on_a_large_scan() {
    let Some(path) = std::env::var_os("MESHPYR_VIEW_LATENCY_MESH") else {
        println!("SKIP: set MESHPYR_VIEW_LATENCY_MESH to a mesh file");
        return;
    };
    let Some(driver) = driver_or_skip("equalizer_latency_on_a_large_scan") else {
        return;
    };
    let input = meshpyr::read_mesh(&path).unwrap();
    let start = Instant::now();
    let pyramid = Pyramid::build(&input).unwrap();
    println!(
        "{} vertices, pyramid built in {:.1} s",
        input.n_vertices(),
        start.elapsed().as_secs_f64()
    );
    let server = meshpyr::view::ViewServer::bind(pyramid, 0).unwrap();
    let url = server.url();
    std::thread::spawn(move || server.run());
    driver.navigate(&url);
    driver.wait_for("window.meshpyr && window.meshpyr.ready && window.meshpyr.idle()");
    let n = driver
        .script("return window.meshpyr.gains.length;")
        .as_u64()
        .unwrap() as usize;
    let mut all = Vec::new();
    println!("octave  gain  end-to-end ms  synthesis ms  received ms  normals+upload ms  draw ms");
    for band in (0..n).rev() {
        for gain in [1.5, 1.0] {
            driver.slide(&format!("#bands input[data-band='{band}']"), gain);
            let last = driver.script("return window.meshpyr.latencies.at(-1);");
            let [ms, synth, received, upload, draw] =
                ["ms", "synthesisMs", "receivedMs", "uploadMs", "drawMs"]
                    .map(|k| last[k].as_f64().unwrap());
            println!(
                "{band:>6}  {gain:>4}  {ms:>13.1}  {synth:>12.1}  {received:>11.1}  {upload:>17.1}  {draw:>7.1}"
            );
            all.push(ms);
        }
    }
    all.sort_by(f64::total_cmp);
    println!(
        "median {:.1} ms, max {:.1} ms over {} slider moves",
        all[all.len() / 2],
        all[all.len() - 1],
        all.len()
    );
}
