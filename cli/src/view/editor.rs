//! The editor without HTTP: [`Editor`] answers the page's `/api` requests in-process, with the
//! same handlers as [`ViewServer`](super::ViewServer), for hosts that carry the requests
//! themselves (the Python package's notebook widget sends them as widget messages). It also
//! gives the page with its script inlined ([`page_html`]) and a self-contained snapshot of a
//! result ([`Editor::snapshot_html`]) that needs no server at all.

use super::api;
use super::guard;
use super::reply::Reply;
use super::session::Session;
use super::state::EditorState;
use glam::DVec3;
use meshpyr::pyramid::Pyramid;
use std::sync::Arc;

/// One answer of [`Editor::request`]: what the HTTP server would have sent.
#[derive(Clone, Debug, PartialEq)]
pub struct Answer {
    /// The HTTP status (200, or a 4xx/5xx with a `{"error": …}` JSON body).
    pub status: u16,
    /// The body's media type.
    pub content_type: String,
    /// The endpoint's own headers (`X-Meshpyr-Version`, `Server-Timing`, …), without the
    /// fixed safety headers of the HTTP server.
    pub headers: Vec<(String, String)>,
    /// The body.
    pub body: Vec<u8>,
}

impl From<Reply> for Answer {
    fn from(reply: Reply) -> Answer {
        Answer {
            status: reply.status,
            content_type: reply.content_type.to_string(),
            headers: reply
                .headers
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
            body: reply.body,
        }
    }
}

/// The editor's state and handlers for one mesh, without a server: each
/// [`Editor::request`] is one `/api` call of `docs/view-api.md`. Whoever carries the requests
/// decides who may send them (the HTTP server checks `Host` and the token first).
pub struct Editor {
    session: Session,
}

impl Editor {
    /// The editor of `pyramid` (shared: the caller may keep using it), named "mesh", with the
    /// default display budget.
    pub fn new(pyramid: Arc<Pyramid>) -> Editor {
        Editor {
            session: Session::new(pyramid),
        }
    }

    /// Names the mesh (shown on the page and in export file names).
    pub fn with_name(mut self, name: &str) -> Editor {
        self.session.name = name.to_string();
        self
    }

    /// Sets the display budget in triangles, as [`ViewServer::with_budget`](super::ViewServer::with_budget).
    pub fn with_budget(mut self, triangles: usize) -> Editor {
        self.session.budget = triangles;
        self
    }

    /// The octave bands `(from, to]` of the equalizer's sliders, as levels (vertex counts).
    pub fn octaves(&self) -> &[(usize, usize)] {
        &self.session.octaves
    }

    /// Answers `method` on `target` (`/api/…` with its query, as in a URL) with `body`, under
    /// the HTTP server's caps on URL and body sizes.
    pub fn request(&mut self, method: &str, target: &str, body: &[u8]) -> Answer {
        if target.len() > api::limits::URL_BYTES {
            return Reply::error(414, "URL too long").into();
        }
        if body.len() > api::limits::BODY_BYTES {
            let cap = api::limits::BODY_BYTES;
            return Reply::error(413, format!("body over {cap} bytes")).into();
        }
        let (path, query) = target.split_once('?').unwrap_or((target, ""));
        if !path.starts_with("/api/") {
            return Reply::error(404, format!("no endpoint {path}")).into();
        }
        let query = guard::parse_query(query);
        answer_api(&mut self.session, method, path, &query, body).into()
    }

    /// Checks an editor state given as the JSON body of `POST /api/edit`
    /// (`{"gains": [...], "normal_only": bool, "moves": [...]}`): the message of the 400 the
    /// server would answer when it is refused.
    pub fn check_state(&self, state: &[u8]) -> Result<(), String> {
        self.parse(state).map(|_| ())
    }

    /// The exact result of an editor state (JSON as in [`Editor::check_state`]) at full
    /// resolution: the input's vertices in the input's order, the positions `meshpyr filter`
    /// or `meshpyr edit` would write for it.
    pub fn positions(&mut self, state: &[u8]) -> Result<Vec<DVec3>, String> {
        let state = self.parse(state)?;
        self.session.positions(state)
    }

    /// A self-contained HTML page that shows the result of `state` (JSON as in
    /// [`Editor::check_state`]) with the editor's view (orbit, zoom, shading, wireframe) and
    /// needs no server: the triangles and f32 positions are inlined. A scan over the display
    /// budget is saved as the level of detail the editor shows, with the exact result's
    /// positions at its vertices; a textured scan is saved without its images.
    pub fn snapshot_html(&mut self, state: &[u8]) -> Result<String, String> {
        let state = self.parse(state)?;
        let mut info = self.session.info();
        // A saved page carries no images: it draws the surface plain.
        info["texture"] = serde_json::Value::Null;
        let (faces, positions) = match self.session.display() {
            None => {
                let positions = self.session.positions(state)?;
                (self.session.faces(), positions)
            }
            Some(display) => {
                let shown = u32::from_le_bytes(display[0..4].try_into().expect("4 bytes"));
                let signal = self.session.exact_signal(&state)?;
                info["display"] = serde_json::json!({
                    "budget": self.session.budget, "lod": false, "shown": shown,
                });
                (display[8..].to_vec(), signal[..shown as usize].to_vec())
            }
        };
        let mut bytes = Vec::with_capacity(12 * positions.len());
        super::session::push_f32_bytes(&mut bytes, &positions);
        let data = format!(
            "const MESHPYR_SNAPSHOT = {{info: {}, faces: '{}', positions: '{}'}};\n",
            info,
            base64(&faces),
            base64(&bytes)
        );
        Ok(page_html(&(data + SNAPSHOT_JS)))
    }

    fn parse(&self, state: &[u8]) -> Result<EditorState, String> {
        api::parse_state(&self.session, state, true).map_err(|refused| {
            serde_json::from_slice::<serde_json::Value>(&refused.body)
                .ok()
                .and_then(|v| v["error"].as_str().map(str::to_string))
                .unwrap_or_else(|| "bad editor state".into())
        })
    }
}

/// Answers an `/api` request admitted by whoever carries it; a bug in a handler becomes a 500
/// instead of taking the editor down with the user's work.
pub(crate) fn answer_api(
    session: &mut Session,
    method: &str,
    path: &str,
    query: &[(String, String)],
    body: &[u8],
) -> Reply {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        api::dispatch(session, method, path, query, body)
    }))
    .unwrap_or_else(|_| Reply::error(500, "internal error (please report)"))
}

/// The script of [`Editor::snapshot_html`]'s page: answers the page's requests from the
/// inlined data, and hides the panel (its controls need the server).
const SNAPSHOT_JS: &str = include_str!("assets/snapshot.js");

/// The editor's page as one HTML document: `index.html` with `script` (run first, in the
/// page's global scope: a host installs its transport there, see `docs/view-api.md`) and then
/// `app.js` inlined. `script` must not contain `</script`.
pub fn page_html(script: &str) -> String {
    let page = super::INDEX_HTML.replace(
        "<script src=\"app.js\"></script>",
        &format!(
            "<script>\n{script}\n</script>\n<script>\n{}</script>",
            super::APP_JS
        ),
    );
    debug_assert!(page.contains(super::APP_JS), "index.html loads app.js");
    page
}

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for (i, shift) in [18, 12, 6, 0].into_iter().enumerate() {
            if i <= chunk.len() {
                out.push(DIGITS[(n >> shift) as usize & 63] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_the_rfc_4648_vectors() {
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, coded) in cases {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
    }

    #[test]
    fn the_inlined_page_carries_the_script_before_app_js() {
        assert!(!super::super::APP_JS.contains("</script"));
        assert!(!SNAPSHOT_JS.contains("</script"));
        let page = page_html("window.hostScript = 1;");
        let host = page.find("window.hostScript = 1;").unwrap();
        let app = page.find(super::super::APP_JS).unwrap();
        assert!(host < app);
        assert!(!page.contains("src=\"app.js\""));
    }
}
