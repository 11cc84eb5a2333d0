//! Who may talk to the server: the `Host` check against DNS rebinding and the per-run token
//! (the defences local notebook servers use), applied before any request reaches a handler.

use super::http::HttpRequest;
use super::reply::Reply;
use std::io::Read;

/// Name of the header that carries the token (the query parameter `token` works too).
pub(crate) const TOKEN_HEADER: &str = "X-Meshpyr-Token";

/// Where an admitted request goes.
pub(crate) enum Route {
    /// The embedded page and script (no token needed: they hold no data).
    Page(String),
    /// An `/api` call: its path and query parameters.
    Api {
        path: String,
        query: Vec<(String, String)>,
    },
}

/// 32 random bytes from the kernel, in hex: unguessable, and readable from the URL bar.
pub(crate) fn random_token() -> std::io::Result<String> {
    let mut bytes = [0u8; 32];
    std::fs::File::open("/dev/urandom")?.read_exact(&mut bytes)?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// Admits `request` or says why not: 403 for a foreign `Host` or, on `/api`, a missing or
/// wrong token; 414 for an overlong URL.
pub(crate) fn check(request: &HttpRequest, port: u16, token: &str) -> Result<Route, Reply> {
    let host = request.header("Host").unwrap_or_default();
    if !host_is_ours(host, port) {
        return Err(Reply::error(
            403,
            format!("this server answers only to 127.0.0.1:{port} and localhost:{port}"),
        ));
    }
    let url = request.target.as_str();
    if url.len() > super::limits::URL_BYTES {
        return Err(Reply::error(414, "URL too long"));
    }
    let (path, query) = url.split_once('?').unwrap_or((url, ""));
    let query = parse_query(query);
    if !path.starts_with("/api/") {
        return Ok(Route::Page(path.to_string()));
    }
    let given = request.header(TOKEN_HEADER).or_else(|| {
        query
            .iter()
            .find(|(k, _)| k == "token")
            .map(|(_, v)| v.as_str())
    });
    if !given.is_some_and(|g| same_secret(g, token)) {
        return Err(Reply::error(
            403,
            "missing or wrong token: open the URL `meshpyr view` printed",
        ));
    }
    Ok(Route::Api {
        path: path.to_string(),
        query,
    })
}

/// True for `127.0.0.1:PORT` and `localhost:PORT` (any case), nothing else.
pub(crate) fn host_is_ours(host: &str, port: u16) -> bool {
    let Some((name, p)) = host.rsplit_once(':') else {
        return false;
    };
    p == port.to_string() && (name == "127.0.0.1" || name.eq_ignore_ascii_case("localhost"))
}

/// Compares in time independent of where the strings differ.
fn same_secret(given: &str, token: &str) -> bool {
    given.len() == token.len()
        && given
            .bytes()
            .zip(token.bytes())
            .fold(0u8, |acc, (a, b)| acc | (a ^ b))
            == 0
}

/// `a=1&b=x` as pairs; values are used as they come (tokens, numbers and format names need
/// no decoding).
pub(crate) fn parse_query(query: &str) -> Vec<(String, String)> {
    query
        .split('&')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (k, v) = p.split_once('=').unwrap_or((p, ""));
            (k.to_string(), v.to_string())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_loopback_names_with_our_port_are_our_host() {
        assert!(host_is_ours("127.0.0.1:8080", 8080));
        assert!(host_is_ours("localhost:8080", 8080));
        assert!(host_is_ours("LocalHost:8080", 8080));
        for foreign in [
            "127.0.0.1:8081",
            "127.0.0.1",
            "localhost",
            "evil.example:8080",
            "localhost.evil.example:8080",
            "127.0.0.1.nip.io:8080",
            "[::1]:8080",
            "",
            ":8080",
        ] {
            assert!(!host_is_ours(foreign, 8080), "{foreign}");
        }
    }

    #[test]
    fn tokens_are_64_hex_digits_and_differ_per_draw() {
        let (a, b) = (random_token().unwrap(), random_token().unwrap());
        assert_eq!(a.len(), 64);
        assert!(a.bytes().all(|c| c.is_ascii_hexdigit()));
        assert_ne!(a, b);
        assert!(same_secret(&a, &a.clone()));
        assert!(!same_secret(&a, &b));
        assert!(!same_secret(&a, &a[1..]));
    }
}
