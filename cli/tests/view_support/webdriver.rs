//! A minimal WebDriver client (W3C WebDriver is plain HTTP/JSON): starts chromedriver and a
//! headless Chromium, runs scripts, sends pointer actions and takes screenshots.

use super::{base64_decode, exchange, request};
use serde_json::{Value, json};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub const ELEMENT: &str = "element-6066-11e4-a52e-4f735466cecf";

fn on_path(names: &[&str]) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| names.iter().map(move |n| dir.join(n)))
        .find(|p| p.is_file())
}

/// A chromedriver process with one Chromium session, both ended on drop.
pub struct Driver {
    port: u16,
    session: String,
    child: Child,
    _profile: tempfile::TempDir,
}

impl Driver {
    /// Starts chromedriver and a headless Chromium, or says why not (missing binaries).
    pub fn start() -> Result<Driver, String> {
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

    pub fn wait_ready(&self) -> Result<(), String> {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(30) {
            let probe = format!(
                "GET /status HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nConnection: close\r\n\r\n",
                self.port
            );
            let up = std::net::TcpStream::connect(("127.0.0.1", self.port)).is_ok()
                && String::from_utf8_lossy(&exchange(
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
    pub fn call(&self, method: &str, path: &str, body: &Value) -> Value {
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

    pub fn call_session(&self, method: &str, path: &str, body: &Value) -> Value {
        self.call(method, &format!("/session/{}{path}", self.session), body)
    }

    pub fn navigate(&self, url: &str) {
        self.call_session("POST", "/url", &json!({ "url": url }));
    }

    /// Runs `body` as a function in the page and returns its result.
    pub fn script(&self, body: &str) -> Value {
        self.call_session(
            "POST",
            "/execute/sync",
            &json!({"script": body, "args": []}),
        )
    }

    /// Runs `body`, which calls `done(result)` when finished.
    pub fn async_script(&self, body: &str) -> Value {
        let script = format!("const done = arguments[arguments.length - 1]; {body}");
        self.call_session(
            "POST",
            "/execute/async",
            &json!({"script": script, "args": []}),
        )
    }

    /// Polls `condition` (a JS expression) until it holds.
    pub fn wait_for(&self, condition: &str) {
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

    pub fn canvas(&self) -> String {
        let found = self.call_session(
            "POST",
            "/element",
            &json!({"using": "css selector", "value": "#canvas"}),
        );
        found[ELEMENT].as_str().unwrap().to_string()
    }

    /// The canvas as RGB pixels.
    pub fn canvas_pixels(&self) -> Vec<u8> {
        let id = self.canvas();
        let shot = self.call_session("GET", &format!("/element/{id}/screenshot"), &Value::Null);
        decode_png(&base64_decode(shot.as_str().unwrap())).1
    }

    pub fn window_png(&self) -> Vec<u8> {
        let shot = self.call_session("GET", "/screenshot", &Value::Null);
        base64_decode(shot.as_str().unwrap())
    }

    pub fn positions(&self) -> Vec<f32> {
        let v = self.script("return Array.from(window.meshpyr.positions);");
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect()
    }

    /// Sets range input `selector` to `value` as a user would and waits for the page to settle.
    pub fn slide(&self, selector: &str, value: f64) {
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

pub fn decode_png(bytes: &[u8]) -> ((u32, u32), Vec<u8>) {
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

/// The driver, or `None` (after printing why) when the browser is missing and not required.
pub fn driver_or_skip(test: &str) -> Option<Driver> {
    match Driver::start() {
        Ok(d) => Some(d),
        Err(why) if std::env::var("MESHPYR_REQUIRE_BROWSER").as_deref() != Ok("1") => {
            println!("SKIP {test}: {why} (set MESHPYR_REQUIRE_BROWSER=1 to fail instead)");
            None
        }
        Err(why) => panic!("{test}: {why}, and MESHPYR_REQUIRE_BROWSER=1"),
    }
}
