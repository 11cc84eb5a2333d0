//! What the editor's session and its previews share: the state the page shows and a clock
//! helper. Both [`super::session`] and [`super::preview`] use it, so the session can use the
//! preview without the preview reaching back into the session.

use meshpyr::pyramid::LevelMove;
use std::time::Instant;

/// What the page shows: one gain per octave, the normal-only switch, the edits so far.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct EditorState {
    pub gains: Vec<f64>,
    pub normal_only: bool,
    pub moves: Vec<LevelMove>,
}

/// Milliseconds from `a` to `b`.
pub(crate) fn ms_between(a: Instant, b: Instant) -> f64 {
    b.duration_since(a).as_secs_f64() * 1e3
}
