//! The little HTTP/1.1 the editor needs, on `std::net`: one thread per connection reads a
//! request (head and body capped, timeouts on both directions), hands it to the server's
//! single worker, and writes the answer back.
//!
//! Written here rather than taken from a crate because the server must survive any client:
//! bodies are read only up to the cap that was checked first, a declared length is never
//! trusted for an allocation, and a stalled client holds only its own thread, and that for
//! a bounded time.

use super::limits;
use super::reply::Reply;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Duration;

/// Longest request head (request line and headers).
const HEAD_BYTES: u64 = 16 * 1024;
/// Most connections served at once; more get 503.
const MAX_CONNECTIONS: usize = 64;
/// Most bytes read off after a refusal.
const LINGER_BYTES: u64 = 16 * 1024 * 1024;
/// How long a connection may sit between bytes.
const IDLE: Duration = Duration::from_secs(30);

/// A request as read from the wire.
pub(crate) struct HttpRequest {
    pub method: String,
    /// The request target as sent (path and query).
    pub target: String,
    pub headers: Vec<(String, String)>,
    pub body: Vec<u8>,
}

impl HttpRequest {
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
}

/// What connection threads send the worker.
pub(crate) enum Message {
    Request(HttpRequest, Sender<Reply>),
    /// The loader of a scan opening in stages is done: the editor's session, or why not.
    Opened(Result<Box<super::session::Session>, String>),
    Stop,
}

/// Accepts connections on `listener` until `stopped`, each on its own thread sending its
/// requests to `worker`.
pub(crate) fn accept(listener: TcpListener, worker: Sender<Message>, stopped: Arc<AtomicBool>) {
    let open = Arc::new(AtomicUsize::new(0));
    for stream in listener.incoming() {
        if stopped.load(Ordering::SeqCst) {
            return;
        }
        let Ok(mut stream) = stream else {
            // Out of descriptors, say: wait rather than spin.
            std::thread::sleep(Duration::from_millis(50));
            continue;
        };
        if open.load(Ordering::SeqCst) >= MAX_CONNECTIONS {
            let _ = write_reply(
                &mut stream,
                Reply::error(503, "too many connections"),
                false,
            );
            continue;
        }
        open.fetch_add(1, Ordering::SeqCst);
        let (worker, open) = (worker.clone(), Arc::clone(&open));
        std::thread::spawn(move || {
            serve_connection(stream, &worker);
            open.fetch_sub(1, Ordering::SeqCst);
        });
    }
}

/// Reads requests from `stream` and answers each with the worker's reply, until the client
/// closes, asks to close, or breaks the protocol.
fn serve_connection(stream: TcpStream, worker: &Sender<Message>) {
    let timeouts = stream
        .set_read_timeout(Some(IDLE))
        .and_then(|_| stream.set_write_timeout(Some(IDLE)));
    let (Ok(()), Ok(read_half)) = (timeouts, stream.try_clone()) else {
        return;
    };
    let mut reader = BufReader::new(read_half);
    let mut writer = stream;
    loop {
        let (request, keep_alive) = match read_request(&mut reader) {
            Ok(Some(read)) => read,
            Ok(None) => return,
            Err(refused) => {
                let _ = write_reply(&mut writer, refused, false);
                linger(&mut reader, &writer);
                return;
            }
        };
        let (answer, reply) = channel();
        if worker.send(Message::Request(request, answer)).is_err() {
            return;
        }
        let Ok(reply) = reply.recv() else { return };
        if write_reply(&mut writer, reply, keep_alive).is_err() || !keep_alive {
            return;
        }
    }
}

/// After refusing a request, reads off (a bounded amount of) what the client is still
/// sending before closing: closing with unread data resets the connection, and the client
/// would lose the refusal.
fn linger(reader: &mut BufReader<TcpStream>, writer: &TcpStream) {
    let _ = writer.shutdown(std::net::Shutdown::Write);
    let _ = writer.set_read_timeout(Some(Duration::from_secs(2)));
    let _ = std::io::copy(&mut reader.take(LINGER_BYTES), &mut std::io::sink());
}

/// The next request and whether the connection stays open after it; `None` when the client
/// closed cleanly before a new request.
fn read_request(reader: &mut BufReader<TcpStream>) -> Result<Option<(HttpRequest, bool)>, Reply> {
    let lines = read_head(reader)?;
    let Some((request_line, header_lines)) = lines.split_first() else {
        return Ok(None);
    };
    let mut parts = request_line.split(' ');
    let (Some(method), Some(target), Some(version), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(Reply::error(400, "malformed request line"));
    };
    if !version.starts_with("HTTP/1.") || method.is_empty() || !target.starts_with('/') {
        return Err(Reply::error(400, "malformed request line"));
    }
    let mut headers = Vec::with_capacity(header_lines.len());
    for line in header_lines {
        let (name, value) = line
            .split_once(':')
            .ok_or_else(|| Reply::error(400, "malformed header"))?;
        headers.push((name.trim().to_string(), value.trim().to_string()));
    }
    let mut request = HttpRequest {
        method: method.to_string(),
        target: target.to_string(),
        headers,
        body: Vec::new(),
    };
    request.body = read_body(reader, &request)?;
    let close = request
        .header("Connection")
        .is_some_and(|c| c.eq_ignore_ascii_case("close"));
    let keep_alive = version == "HTTP/1.1" && !close;
    Ok(Some((request, keep_alive)))
}

/// The head's lines without their line ends; empty when the connection closed first.
fn read_head(reader: &mut BufReader<TcpStream>) -> Result<Vec<String>, Reply> {
    let mut head = Vec::new();
    let mut limited = reader.take(HEAD_BYTES);
    loop {
        let start = head.len();
        let n = limited
            .read_until(b'\n', &mut head)
            .map_err(|_| Reply::error(408, "request not received in time"))?;
        if n == 0 {
            if head.is_empty() {
                return Ok(Vec::new());
            }
            return Err(Reply::error(431, "request head too large or cut short"));
        }
        let line = &head[start..];
        if line == b"\r\n" || line == b"\n" {
            if start == 0 {
                // Blank lines before a request are allowed (RFC 9112 §2.2).
                head.clear();
                continue;
            }
            break;
        }
    }
    let text = std::str::from_utf8(&head).map_err(|_| Reply::error(400, "head is not UTF-8"))?;
    Ok(text
        .lines()
        .map(|l| l.trim_end_matches('\r').to_string())
        .filter(|l| !l.is_empty())
        .collect())
}

/// The body announced by `Content-Length`, refused with 413 before reading when it is over
/// the cap; chunked bodies are refused (the page never sends them).
fn read_body(reader: &mut BufReader<TcpStream>, request: &HttpRequest) -> Result<Vec<u8>, Reply> {
    if request.header("Transfer-Encoding").is_some() {
        return Err(Reply::error(411, "send the body with a Content-Length"));
    }
    let length = match request.header("Content-Length") {
        None => return Ok(Vec::new()),
        Some(text) => text
            .parse::<u64>()
            .map_err(|_| Reply::error(400, "bad Content-Length"))?,
    };
    if length > limits::BODY_BYTES as u64 {
        return Err(Reply::error(
            413,
            format!("body over {} bytes", limits::BODY_BYTES),
        ));
    }
    let mut body = Vec::with_capacity(length as usize);
    reader
        .take(length)
        .read_to_end(&mut body)
        .map_err(|_| Reply::error(408, "body not received in time"))?;
    if body.len() as u64 != length {
        return Err(Reply::error(400, "body shorter than its Content-Length"));
    }
    Ok(body)
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        411 => "Length Required",
        413 => "Content Too Large",
        414 => "URI Too Long",
        422 => "Unprocessable Content",
        431 => "Request Header Fields Too Large",
        503 => "Service Unavailable",
        _ => "Internal Server Error",
    }
}

fn write_reply(stream: &mut TcpStream, reply: Reply, keep_alive: bool) -> std::io::Result<()> {
    let mut head = format!(
        "HTTP/1.1 {} {}\r\nContent-Length: {}\r\nConnection: {}\r\n",
        reply.status,
        reason(reply.status),
        reply.body.len(),
        if keep_alive { "keep-alive" } else { "close" }
    );
    for (name, value) in reply.all_headers() {
        head += &format!("{name}: {value}\r\n");
    }
    head += "\r\n";
    stream.write_all(head.as_bytes())?;
    stream.write_all(&reply.body)?;
    stream.flush()
}

/// The worker's end of the channel, and the sending end for the acceptor and stoppers.
pub(crate) fn worker_channel() -> (Sender<Message>, Receiver<Message>) {
    channel()
}
