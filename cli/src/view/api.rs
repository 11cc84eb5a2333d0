//! The `/api` endpoints: request parsing with caps on every size and number, and dispatch to
//! the [`Session`]. Every refusal is a 4xx with `{"error": …}`.

use super::reply::Reply;
use super::session::{EditorState, Session, ms_between, push_f32_bytes};
use glam::DVec3;
use meshpyr::pyramid::{LevelMove, MoveHandle};
use serde::Deserialize;
use std::time::Instant;

/// The caps on what a client may send.
pub mod limits {
    /// Largest request body in bytes.
    pub const BODY_BYTES: usize = 256 * 1024;
    /// Longest request URL in bytes.
    pub const URL_BYTES: usize = 2048;
    /// Largest gain of an octave (the equalizer's range is `0..=MAX_GAIN`).
    pub const MAX_GAIN: f64 = 3.0;
    /// Most edits (moves) in one request.
    pub const MAX_MOVES: usize = 256;
    /// Largest edit radius and displacement, in bounding-box diagonals.
    pub const MAX_REACH: f64 = 10.0;
}

/// The JSON of `POST /api/filter`, `/api/edit` and `/api/export`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StateRequest {
    gains: Vec<f64>,
    #[serde(default)]
    normal_only: bool,
    #[serde(default)]
    moves: Vec<MoveRequest>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MoveRequest {
    level: usize,
    center: [f64; 3],
    displacement: [f64; 3],
    radius: f64,
}

pub(crate) fn dispatch(
    session: &mut Session,
    method: &str,
    path: &str,
    query: &[(String, String)],
    body: &[u8],
) -> Reply {
    let param = |name: &str| {
        query
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    };
    let result = match (method, path) {
        ("GET", "/api/info") => Ok(Reply::json(&session.info())),
        ("GET", "/api/faces") => Ok(Reply::binary(session.faces())),
        ("GET", "/api/level") => level(session, param("n")),
        ("POST", "/api/filter") => {
            parse_state(session, body, false).and_then(|state| positions(session, state))
        }
        ("POST", "/api/edit") => {
            parse_state(session, body, true).and_then(|state| positions(session, state))
        }
        ("GET", "/api/export") => {
            let last = session.last.clone();
            export(session, last, param("format"))
        }
        ("POST", "/api/export") => parse_state(session, body, true)
            .and_then(|state| export(session, state, param("format"))),
        (_, "/api/info" | "/api/faces" | "/api/level" | "/api/filter" | "/api/edit")
        | (_, "/api/export") => Err(Reply::error(405, format!("{method} not allowed on {path}"))),
        _ => Err(Reply::error(404, format!("no endpoint {path}"))),
    };
    result.unwrap_or_else(|refused| refused)
}

fn bad(message: impl std::fmt::Display) -> Reply {
    Reply::error(400, message)
}

fn parse_state(session: &Session, body: &[u8], moves_allowed: bool) -> Result<EditorState, Reply> {
    let req: StateRequest =
        serde_json::from_slice(body).map_err(|e| bad(format!("bad JSON body: {e}")))?;
    let octaves = session.octaves.len();
    if req.gains.len() != octaves {
        return Err(bad(format!(
            "expected {octaves} gains (one per octave), got {}",
            req.gains.len()
        )));
    }
    if let Some(g) = req
        .gains
        .iter()
        .find(|g| !(0.0..=limits::MAX_GAIN).contains(*g))
    {
        return Err(bad(format!("gain {g} is outside 0..={}", limits::MAX_GAIN)));
    }
    if !moves_allowed && !req.moves.is_empty() {
        return Err(bad("/api/filter takes no moves; use /api/edit"));
    }
    if req.moves.len() > limits::MAX_MOVES {
        return Err(bad(format!("at most {} moves", limits::MAX_MOVES)));
    }
    let moves = req
        .moves
        .iter()
        .map(|m| check_move(session, m))
        .collect::<Result<_, _>>()?;
    Ok(EditorState {
        gains: req.gains,
        normal_only: req.normal_only,
        moves,
    })
}

fn check_move(session: &Session, m: &MoveRequest) -> Result<LevelMove, Reply> {
    let levels = session.pyramid.levels();
    if !levels.contains(&m.level) {
        return Err(bad(format!(
            "move level {} is outside {}..={}",
            m.level,
            levels.start(),
            levels.end()
        )));
    }
    let reach = limits::MAX_REACH * session.pyramid.pyramid.bbox_diagonal();
    let (center, displacement) = (DVec3::from(m.center), DVec3::from(m.displacement));
    let sane = center.is_finite()
        && displacement.is_finite()
        && displacement.length() <= reach
        && m.radius > 0.0
        && m.radius <= reach;
    if !sane {
        return Err(bad(format!(
            "a move needs a finite centre, a displacement up to {reach} and a radius in (0, {reach}]"
        )));
    }
    Ok(LevelMove {
        level: m.level,
        handle: MoveHandle {
            center,
            displacement,
            radius: m.radius,
        },
    })
}

/// f32 positions of the input's vertices, with the server's time in headers: in all
/// (`X-Meshpyr-Synthesis-Ms`, kept for scripts that read it) and by part (`Server-Timing`).
fn positions(session: &mut Session, state: EditorState) -> Result<Reply, Reply> {
    let (positions, timing) = session.positions_timed(state).map_err(bad)?;
    let start = Instant::now();
    let mut body = Vec::new();
    push_f32_bytes(&mut body, &positions);
    let encode = ms_between(start, Instant::now());
    let (synthesis, reorder) = (timing.synthesis, timing.reorder);
    Ok(Reply::binary(body)
        .with_header(
            "X-Meshpyr-Synthesis-Ms",
            format!("{:.1}", synthesis + reorder),
        )
        .with_header(
            "Server-Timing",
            format!(
                "synthesis;dur={synthesis:.1}, reorder;dur={reorder:.1}, encode;dur={encode:.1}"
            ),
        ))
}

fn level(session: &Session, n: Option<&str>) -> Result<Reply, Reply> {
    let levels = session.pyramid.levels();
    let n: usize = n
        .and_then(|n| n.parse().ok())
        .filter(|n| levels.contains(n))
        .ok_or_else(|| {
            bad(format!(
                "level needs n in {}..={}",
                levels.start(),
                levels.end()
            ))
        })?;
    Ok(Reply::binary(session.level(n)))
}

fn export(session: &mut Session, state: EditorState, format: Option<&str>) -> Result<Reply, Reply> {
    let format = format.unwrap_or("ply");
    if !["ply", "obj", "pyr"].contains(&format) {
        return Err(bad(format!(
            "unknown export format {format:?} (ply, obj or pyr)"
        )));
    }
    let (bytes, file) = session
        .export(state, format)
        .map_err(|e| Reply::error(422, e))?;
    Ok(Reply::binary(bytes).with_header(
        "Content-Disposition",
        format!("attachment; filename=\"{file}\""),
    ))
}
