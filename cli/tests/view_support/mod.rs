//! Helpers shared by the `meshpyr view` tests: a minimal HTTP/1.1 client on `TcpStream` (for the
//! editor's API and for WebDriver, which is plain HTTP/JSON), and a server started on a mesh.
#![allow(dead_code)]

pub mod webdriver;

use meshpyr::Pyramid;
use meshpyr_cli::view::ViewServer;
use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::time::Duration;

/// Path of a file in `tests/data`.
pub fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(name)
}

/// A running editor: its port and token. The server thread lives as long as the test process.
pub struct Running {
    pub port: u16,
    pub token: String,
    pub url: String,
}

/// Starts the editor on `mesh` (a file in `tests/data`) on a free port.
pub fn serve(mesh: &str) -> Running {
    serve_with_budget(mesh, meshpyr_cli::view::DEFAULT_BUDGET)
}

/// [`serve`] with a display budget of `triangles`.
pub fn serve_with_budget(mesh: &str, triangles: usize) -> Running {
    let input = meshpyr::read_mesh(data(mesh)).expect("test mesh");
    let server = ViewServer::bind(Pyramid::build(&input).expect("pyramid"), 0)
        .expect("bind")
        .with_name(mesh)
        .with_budget(triangles);
    let running = Running {
        port: server.port(),
        token: server.token().to_string(),
        url: server.url(),
    };
    std::thread::spawn(move || server.run());
    running
}

/// An HTTP answer.
#[derive(Debug)]
pub struct Response {
    pub status: u16,
    pub headers: Vec<(String, String)>,
    pub body: Vec<u8>,
}

impl Response {
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }

    pub fn json(&self) -> serde_json::Value {
        serde_json::from_slice(&self.body).unwrap_or_else(|e| {
            panic!(
                "not JSON ({e}): {}",
                String::from_utf8_lossy(&self.body[..self.body.len().min(300)])
            )
        })
    }

    pub fn f32s(&self) -> Vec<f32> {
        self.body
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }
}

/// Sends raw bytes to `port`, says that nothing more is coming, and reads the answer to the end.
pub fn raw(port: u16, request: &[u8]) -> Vec<u8> {
    raw_waiting(port, request, Duration::from_secs(300))
}

/// [`raw`], giving up on the answer after `wait`.
pub fn raw_waiting(port: u16, request: &[u8], wait: Duration) -> Vec<u8> {
    exchange(port, request, wait, true)
}

/// Sends `request` and reads until the server closes; `half_close` shuts our sending side
/// first, so that a server waiting for a promised body sees its end (WebDriver servers take a
/// half-closed connection as gone, so requests do not).
pub fn exchange(port: u16, request: &[u8], wait: Duration, half_close: bool) -> Vec<u8> {
    let mut stream = TcpStream::connect(("127.0.0.1", port)).expect("connect");
    stream.set_read_timeout(Some(wait)).unwrap();
    // A server may refuse and close before reading all of it; its answer is still there.
    let _ = stream.write_all(request);
    if half_close {
        let _ = stream.shutdown(std::net::Shutdown::Write);
    }
    read_answer(&mut stream)
}

/// Reads one response: to the end of its `Content-Length` or of its last chunk (servers may
/// keep the connection open whatever the request asked), or else until the server closes.
fn read_answer(stream: &mut TcpStream) -> Vec<u8> {
    let mut answer = Vec::new();
    let mut buf = [0u8; 64 * 1024];
    loop {
        if answer_complete(&answer) {
            return answer;
        }
        match stream.read(&mut buf) {
            Ok(n) if n > 0 => answer.extend_from_slice(&buf[..n]),
            _ => return answer,
        }
    }
}

fn answer_complete(bytes: &[u8]) -> bool {
    let Some(split) = bytes.windows(4).position(|w| w == b"\r\n\r\n") else {
        return false;
    };
    let head = String::from_utf8_lossy(&bytes[..split]).to_ascii_lowercase();
    let body = &bytes[split + 4..];
    if let Some(length) = head
        .lines()
        .find_map(|l| l.strip_prefix("content-length:"))
        .and_then(|v| v.trim().parse::<usize>().ok())
    {
        return body.len() >= length;
    }
    head.contains("transfer-encoding: chunked") && body.ends_with(b"0\r\n\r\n")
}

/// One request; `headers` may override `Host`.
pub fn request(
    port: u16,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> Response {
    let mut head = format!("{method} {path} HTTP/1.1\r\nConnection: close\r\n");
    if !headers.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
        head += &format!("Host: 127.0.0.1:{port}\r\n");
    }
    for (k, v) in headers {
        head += &format!("{k}: {v}\r\n");
    }
    head += &format!("Content-Length: {}\r\n\r\n", body.len());
    let mut bytes = head.into_bytes();
    bytes.extend_from_slice(body);
    parse_response(&exchange(port, &bytes, Duration::from_secs(300), false))
}

/// Parses a whole HTTP/1.1 response, chunked or not.
pub fn parse_response(bytes: &[u8]) -> Response {
    let split = bytes
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .unwrap_or_else(|| panic!("no HTTP head in {:?}", String::from_utf8_lossy(bytes)));
    let head = String::from_utf8_lossy(&bytes[..split]).into_owned();
    let mut lines = head.split("\r\n");
    let status = lines
        .next()
        .and_then(|l| l.split(' ').nth(1))
        .and_then(|s| s.parse().ok())
        .expect("status line");
    let headers: Vec<(String, String)> = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        .collect();
    let rest = &bytes[split + 4..];
    let chunked = headers
        .iter()
        .any(|(k, v)| k.eq_ignore_ascii_case("transfer-encoding") && v.contains("chunked"));
    let body = if chunked {
        dechunk(rest)
    } else {
        rest.to_vec()
    };
    Response {
        status,
        headers,
        body,
    }
}

fn dechunk(mut rest: &[u8]) -> Vec<u8> {
    let mut body = Vec::new();
    loop {
        let Some(eol) = rest.windows(2).position(|w| w == b"\r\n") else {
            return body;
        };
        let size_text = String::from_utf8_lossy(&rest[..eol]);
        let size = usize::from_str_radix(size_text.split(';').next().unwrap().trim(), 16)
            .expect("chunk size");
        if size == 0 {
            return body;
        }
        body.extend_from_slice(&rest[eol + 2..eol + 2 + size]);
        rest = &rest[eol + 2 + size + 2..];
    }
}

impl Running {
    /// A request with the token header.
    pub fn api(&self, method: &str, path: &str, body: &[u8]) -> Response {
        request(
            self.port,
            method,
            path,
            &[("X-Meshpyr-Token", &self.token)],
            body,
        )
    }

    /// Polls `/api/status` until `done` holds (the server's work ends in bounded time on the
    /// test meshes; the test's own timeout is the bound).
    pub fn wait_status(&self, done: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        loop {
            let status = self.api("GET", "/api/status", b"").json();
            if done(&status) {
                return status;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

/// The octaves `(from, to)` of an `/api/info` answer.
pub fn octaves_of(info: &serde_json::Value) -> Vec<(usize, usize)> {
    info["octaves"]
        .as_array()
        .expect("octaves")
        .iter()
        .map(|o| {
            (
                o["from"].as_u64().unwrap() as usize,
                o["to"].as_u64().unwrap() as usize,
            )
        })
        .collect()
}

/// The positions of a PLY file's bytes (an export), as f32 values.
pub fn ply_f32s(bytes: &[u8]) -> Vec<f32> {
    let mesh = meshpyr::io::read_mesh_bytes(bytes, meshpyr::io::MeshFormat::Ply).expect("PLY");
    mesh.positions
        .iter()
        .flat_map(|p| p.to_array().map(|x| x as f32))
        .collect()
}

/// Decodes standard base64 (WebDriver screenshots, bytes returned by scripts).
pub fn base64_decode(text: &str) -> Vec<u8> {
    let value = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => (c - b'A') as u32,
            b'a'..=b'z' => (c - b'a' + 26) as u32,
            b'0'..=b'9' => (c - b'0' + 52) as u32,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let clean: Vec<u8> = text.bytes().filter(|&c| c != b'=' && c > b' ').collect();
    let mut out = Vec::with_capacity(clean.len() * 3 / 4);
    for chunk in clean.chunks(4) {
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= value(c) << (18 - 6 * i);
        }
        let bytes = acc.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    out
}

/// The bits of `positions` rounded to f32, as the API sends them (x, y, z of each in turn).
pub fn f32_bits(positions: &[glam::DVec3]) -> Vec<u32> {
    positions
        .iter()
        .flat_map(|p| p.to_array().map(|x| (x as f32).to_bits()))
        .collect()
}

/// The bits of f32 values, to compare them exactly.
pub fn bits(values: &[f32]) -> Vec<u32> {
    values.iter().map(|x| x.to_bits()).collect()
}
