//! The Burt–Adelson detail pyramid on a progressive mesh (Guskov–Sweldens–Schröder 1999;
//! `algorithms.md` §1c): a space-frequency decomposition of a surface into a coarse base signal
//! plus, for every vertex split, the details that the relaxation-based prediction misses.
//!
//! * [`analysis`]: finest → coarsest, vertex by vertex — presmooth the 1-ring, collapse, predict
//!   the removed vertex and then its 1-ring, store the differences in local frames.
//! * [`synthesis`]: coarsest → finest — split, predict exactly as in the analysis, add the
//!   (scaled) details back. With unit gains it reproduces the input to rounding.
//! * [`frames`]: the local frames the details live in, built from the *predicted* geometry so
//!   that synthesis can rebuild them before the details are known.
//! * [`gains`]: filters as a gain per level (low-pass, stop-band, enhancement, bands in vertex
//!   counts or feature sizes).
//! * [`edit`]: multiresolution editing — move vertices of a coarse level, resynthesise, and the
//!   details ride along in their frames.
//! * [`spectrum`]: detail energy per level band, as a table and a chart.
//! * [`pipeline`]: file-level glue — polygon mesh in, polygon mesh out in the input's exact
//!   vertex and face order.
//!
//! Levels are vertex counts, as in the paper: level `n` is the mesh of the first `n` PM
//! vertices, and the details of level `n` are those stored by the split that creates vertex
//! `n − 1`.
//!
//! The relaxation weights of a level depend only on its connectivity and on the original
//! positions, never on the signal, so the analysis records them (with the 1-ring fans the frames
//! need) in flat arrays. Synthesis — every re-filtering and every edit — then runs on those
//! arrays alone, without touching the half-edge mesh.

pub mod analysis;
pub mod edit;
pub mod frames;
pub mod gains;
pub mod pipeline;
pub mod spectrum;
pub mod synthesis;

pub use edit::{MoveHandle, falloff};
pub use gains::{Filter, GainBand, GainParseError, LevelGains, LevelSpec};
pub use pipeline::{PyramidOptions, ScanPyramid};
pub use spectrum::{BandEnergy, Spectrum};

use crate::pm::PmError;
use glam::DVec3;

/// Why a pyramid could not be built or used.
#[derive(Debug, thiserror::Error)]
pub enum PyramidError {
    /// The relaxation operator cannot be written as per-vertex linear weights.
    #[error(
        "the `{0}` relaxation is not linear in the signal; the detail pyramid needs an operator with fixed per-level weights"
    )]
    NonLinearRelaxation(&'static str),
    /// The mesh could not be turned into a half-edge mesh.
    #[error("cannot build the mesh: {0}")]
    Build(#[from] crate::mesh::BuildError),
    /// The progressive mesh could not be built.
    #[error("cannot build the progressive mesh: {0}")]
    Pm(#[from] PmError),
    /// A signal or edit does not fit the pyramid.
    #[error("{0}")]
    Invalid(String),
    /// A broken internal invariant; please report.
    #[error("internal error in the detail pyramid (please report): {0}")]
    Internal(String),
}

/// A Burt–Adelson detail pyramid: base signal, details, and the per-level weights and fans
/// synthesis needs. Build one with [`Pyramid::analyze`]; see the [module docs](self).
///
/// All vertex indices are PM indices. Per-split data is stored in analysis order (finest split
/// first); [`Pyramid::split_slot`] maps a split index to its storage slot.
#[derive(Clone, Debug)]
pub struct Pyramid {
    pub(crate) n_base: usize,
    pub(crate) n_finest: usize,
    /// Signal values of the vertices with no face (PM indices `n_finest..`), passed through.
    pub(crate) passthrough: Vec<DVec3>,
    /// The base signal `f^(n0)` on PM vertices `0..n_base`.
    pub(crate) base: Vec<DVec3>,
    /// Per storage slot: the survivor `t_n` of the split (the frame reference of the new vertex).
    pub(crate) survivor: Vec<u32>,
    /// Per storage slot: range into `touched` (the new vertex first, then its 1-ring CCW).
    pub(crate) touched_start: Vec<u32>,
    pub(crate) touched: Vec<u32>,
    /// Per touched entry: range into the stencil arrays (empty = the operator keeps the value).
    pub(crate) stencil_start: Vec<u32>,
    pub(crate) stencil_vertex: Vec<u32>,
    pub(crate) stencil_weight: Vec<f64>,
    /// Per touched entry: range into `fan` (its 1-ring at the split's level, CCW).
    pub(crate) fan_start: Vec<u32>,
    pub(crate) fan: Vec<u32>,
    /// Per touched entry: the fan has a boundary gap between its last and first neighbour.
    pub(crate) fan_open: Vec<bool>,
    /// Per touched entry: the detail in the entry's local frame `(t1, t2, n)`.
    pub(crate) details: Vec<DVec3>,
    pub(crate) relaxation: &'static str,
    pub(crate) surface_area: f64,
    pub(crate) bbox_diagonal: f64,
}

impl Pyramid {
    /// Number of vertices of the coarsest level, `n0`.
    pub fn n_base_vertices(&self) -> usize {
        self.n_base
    }

    /// Number of vertices of the finest level (vertices referenced by a face).
    pub fn n_vertices(&self) -> usize {
        self.n_finest
    }

    /// Length of the signals [`Pyramid::synthesize`] returns: the finest level plus the vertices
    /// no face refers to (which pass through unchanged).
    pub fn signal_len(&self) -> usize {
        self.n_finest + self.passthrough.len()
    }

    /// Number of vertex splits (`n_vertices() − n_base_vertices()`).
    pub fn n_splits(&self) -> usize {
        self.survivor.len()
    }

    /// Name of the relaxation operator the pyramid was analysed with.
    pub fn relaxation(&self) -> &'static str {
        self.relaxation
    }

    /// Total area of the finest mesh (model units²); converts feature sizes to levels.
    pub fn surface_area(&self) -> f64 {
        self.surface_area
    }

    /// Bounding-box diagonal of the finest mesh's original positions.
    pub fn bbox_diagonal(&self) -> f64 {
        self.bbox_diagonal
    }

    /// The base signal `f^(n0)` (PM vertices `0..n0`).
    pub fn base(&self) -> &[DVec3] {
        &self.base
    }

    /// Total number of stored detail vectors (about 7 per vertex: the pyramid is oversampled).
    pub fn n_details(&self) -> usize {
        self.details.len()
    }

    /// Storage slot of split `k` (split `k` creates vertex `n0 + k`, level `n0 + k + 1`).
    #[inline]
    pub fn split_slot(&self, k: usize) -> usize {
        self.survivor.len() - 1 - k
    }

    /// The level (vertex count) whose details split `k` carries.
    #[inline]
    pub fn level_of_split(&self, k: usize) -> usize {
        self.n_base + k + 1
    }

    /// The vertices whose values split `k` sets (the new vertex first, then its 1-ring) and
    /// their details in local frames `(t1, t2, n)`.
    pub fn split_details(&self, k: usize) -> (&[u32], &[DVec3]) {
        let s = self.split_slot(k);
        let r = self.touched_start[s] as usize..self.touched_start[s + 1] as usize;
        (&self.touched[r.clone()], &self.details[r])
    }

    /// Approximate heap memory in bytes (weights, fans, details).
    pub fn memory_bytes(&self) -> usize {
        4 * (self.survivor.len()
            + self.touched_start.len()
            + self.touched.len()
            + self.stencil_start.len()
            + self.stencil_vertex.len()
            + self.fan_start.len()
            + self.fan.len())
            + 8 * self.stencil_weight.len()
            + self.fan_open.len()
            + 24 * (self.details.len() + self.base.len() + self.passthrough.len())
    }
}
