//! The `/api` endpoints: request parsing with caps on every size and number, and dispatch to
//! the [`Session`]. Every refusal is a 4xx with `{"error": …}`.

use super::opening::Opening;
use super::reply::Reply;
use super::session::{Session, push_f32_bytes};
use super::state::{EditorState, ms_between};
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
    /// The display budget's range, in triangles.
    pub const BUDGET: std::ops::RangeInclusive<usize> = 1_000..=100_000_000;

    /// `Err` with the refusal's words when `triangles` is outside [`BUDGET`].
    pub fn check_budget(triangles: usize) -> Result<(), String> {
        if BUDGET.contains(&triangles) {
            return Ok(());
        }
        Err(format!(
            "budget {triangles} is outside {}..={} triangles",
            BUDGET.start(),
            BUDGET.end()
        ))
    }
}

/// The JSON of `POST /api/budget`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BudgetRequest {
    triangles: usize,
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
    session.poll_layout();
    let result = match (method, path) {
        ("GET", "/api/info") => Ok(Reply::json(&session.info())),
        ("GET", "/api/faces") => Ok(Reply::binary(session.faces())),
        ("GET", "/api/texcoords") => texcoords(session, param("n")),
        ("GET", "/api/texture") => texture_image(session, param("image")),
        ("GET", "/api/level") => level(session, param("n")),
        ("GET", "/api/display") => session
            .display()
            .map(Reply::binary)
            .ok_or_else(within_budget),
        ("POST", "/api/preview") => {
            parse_state(session, body, true).and_then(|state| preview(session, state))
        }
        ("GET", "/api/status") => Ok(Reply::json(&session.status())),
        ("GET", "/api/opening") => {
            Err(Reply::error(409, "the scan is open: its pictures are gone"))
        }
        ("POST", "/api/budget") => serde_json::from_slice::<BudgetRequest>(body)
            .map_err(|e| bad(format!("bad JSON body: {e}")))
            .and_then(|b| {
                limits::check_budget(b.triangles).map_err(bad)?;
                session.set_budget(b.triangles);
                Ok(Reply::json(&session.info()))
            }),
        ("GET", "/api/exact") => exact(session, param("version")),
        ("POST", "/api/filter") => whole(session)
            .and_then(|()| parse_state(session, body, false))
            .and_then(|state| positions(session, state)),
        ("POST", "/api/edit") => whole(session)
            .and_then(|()| parse_state(session, body, true))
            .and_then(|state| positions(session, state)),
        ("GET", "/api/export") => whole(session).and_then(|()| {
            let last = session.last.clone();
            export(session, last, param("format"))
        }),
        ("POST", "/api/export") => whole(session)
            .and_then(|()| parse_state(session, body, true))
            .and_then(|state| export(session, state, param("format"))),
        (_, "/api/info" | "/api/faces" | "/api/level" | "/api/filter" | "/api/edit")
        | (_, "/api/export" | "/api/display" | "/api/preview" | "/api/status" | "/api/exact")
        | (_, "/api/budget" | "/api/opening" | "/api/texcoords" | "/api/texture") => {
            Err(Reply::error(405, format!("{method} not allowed on {path}")))
        }
        _ => Err(Reply::error(404, format!("no endpoint {path}"))),
    };
    result.unwrap_or_else(|refused| refused)
}

/// The answers while the scan opens ([`Opening`]): its status and picture; every other call
/// waits for the editor (503).
pub(crate) fn while_opening(opening: &Opening, method: &str, path: &str) -> Reply {
    match (method, path) {
        ("GET", "/api/status") => Reply::json(&opening.status()),
        ("GET", "/api/opening") => {
            let (bytes, number) = opening.picture_bytes();
            Reply::binary(bytes).with_header("X-Meshpyr-Picture", number.to_string())
        }
        (_, "/api/status" | "/api/opening") => {
            Reply::error(405, format!("{method} not allowed on {path}"))
        }
        _ => Reply::error(
            503,
            format!("the scan is still opening ({})", opening.stage_name()),
        ),
    }
}

/// `Err` with a 503 saying why while the session has only a staged pyramid's first stage.
fn whole(session: &Session) -> Result<(), Reply> {
    match session.pending() {
        Some(why) => Err(Reply::error(503, why)),
        None => Ok(()),
    }
}

fn bad(message: impl std::fmt::Display) -> Reply {
    Reply::error(400, message)
}

pub(crate) fn parse_state(
    session: &Session,
    body: &[u8],
    moves_allowed: bool,
) -> Result<EditorState, Reply> {
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
    let levels = &session.levels;
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

fn untextured() -> Reply {
    Reply::error(
        409,
        "the scan has no texture (texture coordinates and an image)",
    )
}

/// The bytes of image `image` of a textured scan (`/api/info`'s `texture.images` lists them),
/// as its file holds them.
fn texture_image(session: &Session, image: Option<&str>) -> Result<Reply, Reply> {
    let texture = session.texture.as_ref().ok_or_else(untextured)?;
    let n = texture.images.len();
    let image = image
        .and_then(|i| i.parse::<usize>().ok())
        .and_then(|i| texture.images.get(i))
        .ok_or_else(|| bad(format!("texture needs image=K with K in 0..{n}")))?;
    Ok(Reply::bytes(200, image.media_type, image.bytes.clone()))
}

fn within_budget() -> Reply {
    Reply::error(
        409,
        "the scan is within the display budget: the page shows it whole (/api/filter, /api/edit)",
    )
}

/// f32 positions of the shown vertices (PM order) for `state`'s preview, its number
/// (`X-Meshpyr-Version`), whether it is complete (`X-Meshpyr-Preview`) and the server's time.
fn preview(session: &mut Session, state: EditorState) -> Result<Reply, Reply> {
    let previewed = session.preview(state).ok_or_else(within_budget)?;
    let start = Instant::now();
    let mut body = Vec::new();
    push_f32_bytes(&mut body, &previewed.positions);
    let encode = ms_between(start, Instant::now());
    let (synthesis, combine) = (previewed.timing.synthesis, previewed.timing.combine);
    let complete = if previewed.complete {
        "complete"
    } else {
        "partial"
    };
    Ok(Reply::binary(body)
        .with_header("X-Meshpyr-Version", previewed.version.to_string())
        .with_header("X-Meshpyr-Preview", complete.to_string())
        .with_header(
            "Server-Timing",
            format!(
                "synthesis;dur={synthesis:.1}, combine;dur={combine:.1}, encode;dur={encode:.1}"
            ),
        ))
}

/// The exact result at the shown vertices (f32, PM order) for state number `version`, or 409
/// while it is not ready (`/api/status` says when it is).
fn exact(session: &mut Session, version: Option<&str>) -> Result<Reply, Reply> {
    let version: u64 = version
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| bad("exact needs version=N (the X-Meshpyr-Version of a preview)"))?;
    if !session.over_budget() {
        return Err(within_budget());
    }
    let positions = session.exact_shown(version).ok_or_else(|| {
        Reply::error(
            409,
            format!("the exact result of state {version} is not ready"),
        )
    })?;
    let mut body = Vec::new();
    push_f32_bytes(&mut body, &positions);
    Ok(Reply::binary(body).with_header("X-Meshpyr-Version", version.to_string()))
}

fn level(session: &Session, n: Option<&str>) -> Result<Reply, Reply> {
    let n = level_number(session, n)?;
    if n > session.synthesised_levels() {
        whole(session)?;
    }
    Ok(Reply::binary(session.level(n)))
}

/// `/api/texcoords`, of what the page shows or, with `n`, of the scrubber's level `n`.
fn texcoords(session: &mut Session, n: Option<&str>) -> Result<Reply, Reply> {
    if session.texture.is_none() {
        return Err(untextured());
    }
    let level = match n {
        None => None,
        Some(n) => Some(level_number(session, Some(n))?),
    };
    match session.texcoords(level) {
        Some(Ok(layout)) => Ok(Reply::binary(layout)),
        Some(Err(why)) => Err(Reply::error(409, why)),
        None => Err(untextured()),
    }
}

/// The level `n` a call names, within the hierarchy's levels.
fn level_number(session: &Session, n: Option<&str>) -> Result<usize, Reply> {
    let levels = &session.levels;
    n.and_then(|n| n.parse().ok())
        .filter(|n| levels.contains(n))
        .ok_or_else(|| {
            bad(format!(
                "level needs n in {}..={}",
                levels.start(),
                levels.end()
            ))
        })
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
