//! The Burt–Adelson detail pyramid on a progressive mesh (Guskov–Sweldens–Schröder 1999;
//! `docs/algorithms.md` §1c): a space-frequency decomposition of a surface into a coarse base signal
//! plus, for every vertex split, the details that the relaxation-based prediction misses.
//!
//! * `analysis`: finest → coarsest, vertex by vertex — presmooth the 1-ring, collapse, predict
//!   the removed vertex and then its 1-ring, store the differences in local frames.
//! * `synthesis`: coarsest → finest — split, predict exactly as in the analysis, add the
//!   (scaled) details back. With unit gains it reproduces the input to rounding.
//! * `frames`: the local frames the details live in, built from the *predicted* geometry so
//!   that synthesis can rebuild them before the details are known.
//! * `gains`: filters as a gain per level (low-pass, stop-band, enhancement, bands in vertex
//!   counts or feature sizes).
//! * `cached`: re-filtering that resumes from the first level whose gain changed (the
//!   interactive equalizer of `meshpyr view`).
//! * `edit`: multiresolution editing — move vertices of a coarse level, resynthesise, and the
//!   details ride along in their frames.
//! * `spectrum`: detail energy per level band, as a table and a chart.
//! * `pipeline`: file-level glue — polygon mesh in, polygon mesh out in the input's exact
//!   vertex and face order; `.pyr` bytes out through the codec (`crate::format`).
//! * `loaded`, `stored`: a decoded `.pyr` file's records turned into a pyramid, with the
//!   stored details when they fit; `staged`: the same in two stages (the levels a viewer
//!   needs first, then the whole pyramid).
//! * `reported`: the front door's results that carry their warnings and what was reached.
//! * `fuzz`: the body of the `pyramid_ops` fuzz target (`meshpyr::fuzzing::fuzz_pyramid`).
//!
//! Levels are vertex counts, as in the paper: level `n` is the mesh of the first `n` PM
//! vertices, and the details of level `n` are those stored by the split that creates vertex
//! `n − 1`.
//!
//! The relaxation weights of a level depend only on its connectivity and on the original
//! positions, never on the signal, so the analysis records them (with the 1-ring fans the frames
//! need) in flat arrays. Synthesis — every re-filtering and every edit — then runs on those
//! arrays alone, without touching the half-edge mesh.

/// Evaluates `$body` with `$c` bound to the code stream `$codes` (a [`Codes`]) at its width:
/// the one place the three widths are told apart, each arm a monomorphised copy.
macro_rules! with_codes {
    ($codes:expr, $c:ident => $body:expr) => {
        match $codes {
            Codes::Byte($c) => $body,
            Codes::Narrow($c) => $body,
            Codes::Wide($c) => $body,
        }
    };
}

pub(crate) mod analysis;
mod band_check;
mod cached;
mod denoise;
pub(crate) mod edit;
pub(crate) mod frames;
mod fuzz;
pub(crate) mod gains;
mod loaded;
pub(crate) mod pipeline;
mod quantise;
mod reported;
pub(crate) mod spectrum;
mod spill;
mod staged;
mod stored;
pub(crate) mod synthesis;
pub(crate) mod waves;

pub use crate::format::{PyramidOptions, StoredDetails};
pub use cached::SynthesisCache;
pub use denoise::{PyramidDenoise, PyramidDenoised, pyramid_denoise};
pub use edit::{HandleReach, LevelMove, MoveHandle};
pub(crate) use fuzz::{fuzz_loaded_pyr, fuzz_pyramid};
pub use gains::{Filter, LevelGains, LevelSpec};
pub use gains::{GainBand, GainParseError};
pub use loaded::{DetailSource, NO_STORED_DETAILS};
pub use pipeline::{PyrContent, PyrFileError, Pyramid};
pub(crate) use pipeline::{analyze_with, guide_share, relaxation_for};
pub use reported::{Edited, Filtered};
pub use spectrum::BandEnergy;
pub use spectrum::Spectrum;
pub use staged::{PendingLayout, Staged, StagedPyramid};

use crate::pm::PmError;
use glam::DVec3;
use spill::{Placement, Stream, Writer};

/// Why a pyramid could not be built or used.
#[derive(Debug, thiserror::Error)]
pub enum PyramidError {
    /// The input holds no surface (nothing at all, a point cloud, only degenerate faces).
    #[error(transparent)]
    NoSurface(#[from] crate::mesh::MissingSurface),
    /// The mesh could not be turned into a half-edge mesh.
    #[error("cannot build the mesh: {0}")]
    Build(#[from] crate::mesh::BuildError),
    /// The progressive mesh could not be built.
    #[error("cannot build the progressive mesh: {0}")]
    Pm(#[from] PmError),
    /// A signal or edit does not fit the pyramid.
    #[error("{0}")]
    Invalid(String),
    /// The temporary file that holds a large pyramid's layout could not be made, written or
    /// mapped (module `spill`; `TMPDIR` names the directory).
    #[error("cannot use a temporary file for the pyramid's layout: {0}")]
    TempFile(#[from] std::io::Error),
    /// A broken internal invariant; please report.
    #[error("internal error in the detail pyramid (please report): {0}")]
    Internal(String),
}

/// A Burt–Adelson detail pyramid: base signal, details, and the per-level weights and fans
/// synthesis needs. Build one with [`DetailPyramid::analyze`]; see the [module docs](self).
///
/// All vertex indices are PM indices. Per-split data is stored wave by wave (module `waves`:
/// the splits of a wave read nothing another writes, so synthesis may run them at once), each
/// wave in split order, as a few sequential streams, so synthesis reads memory front to back:
///
/// * `locals`: per split, its *local table* — the PM vertices the split reads or writes: the new
///   vertex, its 1-ring counter-clockwise (these `t` are the touched vertices), then every other
///   vertex of their stencils and fans. Synthesis gathers these values once into a small
///   contiguous buffer and works there.
/// * `codes`: per split `[t, survivor]`, then per touched entry `[s, 2·m + open]` followed by
///   `s` stencil and `m` fan indices — all indices into the split's local table, so they are
///   stored in 8 bits when every neighbourhood has fewer than 256 vertices and every valence is
///   below 128 (typical scans), else in 16 bits, and in 32 bits only for extreme valences.
/// * `weights`: per touched entry its `s` stencil weights, in f32. Synthesis applies them
///   anchored at the stencil's first vertex, so their rounding costs a fraction 1e-7 of a
///   stencil's extent, not of the coordinates.
/// * `details`: per touched entry its detail in the local frame `(t1, t2, n)`, in whole
///   `detail_step`s (module `quantise`: quantised in a closed loop, so that the rounding does
///   not add up across levels).
///
/// The first four streams and the offsets do not depend on the signal; a large pyramid keeps
/// them in a temporary file (module `spill`), the details always in memory.
#[derive(Clone, Debug)]
pub struct DetailPyramid {
    pub(crate) n_base: usize,
    pub(crate) n_finest: usize,
    /// Signal values of the vertices with no face (PM indices `n_finest..`), passed through.
    pub(crate) passthrough: Vec<DVec3>,
    /// The base signal `f^(n0)` on PM vertices `0..n_base`.
    pub(crate) base: Vec<DVec3>,
    /// Per slot (plus an end sentinel): where its records start in each stream.
    pub(crate) offsets: Stream<SplitOffsets>,
    pub(crate) locals: Stream<u32>,
    pub(crate) codes: Codes,
    pub(crate) weights: Stream<f32>,
    pub(crate) details: Vec<[i32; 3]>,
    /// The splits grouped into waves of independent splits (parallel synthesis).
    pub(crate) waves: waves::Waves,
    pub(crate) relaxation: &'static str,
    /// The step the details are whole multiples of (a power of two; see `quantise`).
    pub(crate) detail_step: f64,
    pub(crate) surface_area: f64,
    pub(crate) bbox_diagonal: f64,
}

/// Start of one split's records in each stream of a [`DetailPyramid`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(crate) struct SplitOffsets {
    pub locals: usize,
    pub codes: usize,
    pub weights: usize,
    pub details: usize,
}

/// The code stream, as narrow as the largest local index allows.
#[derive(Clone, Debug)]
pub(crate) enum Codes {
    Byte(Stream<u8>),
    Narrow(Stream<u16>),
    Wide(Stream<u32>),
}

/// A code stream being recorded, as narrow as the largest code so far allows.
pub(crate) enum CodesWriter {
    Byte(Writer<u8>),
    Narrow(Writer<u16>),
    Wide(Writer<u32>),
}

/// The element types of [`Codes`]: their slice in a stream of their width, and the stream.
pub(crate) trait CodeWidth: bytemuck::Pod + Sized {
    /// The codes if `codes` has this width, else an empty slice.
    fn of(codes: &Codes) -> &[Self];
    /// The stream of these codes.
    fn wrap(codes: Stream<Self>) -> Codes;
}

macro_rules! code_width {
    ($t:ty, $variant:ident) => {
        impl CodeWidth for $t {
            fn of(codes: &Codes) -> &[$t] {
                match codes {
                    Codes::$variant(c) => c,
                    _ => &[],
                }
            }
            fn wrap(codes: Stream<$t>) -> Codes {
                Codes::$variant(codes)
            }
        }
    };
}
code_width!(u8, Byte);
code_width!(u16, Narrow);
code_width!(u32, Wide);

impl Codes {
    fn bytes(&self) -> usize {
        with_codes!(self, c => c.bytes())
    }

    /// Largest code the current width holds.
    fn capacity_max(&self) -> u32 {
        match self {
            Codes::Byte(_) => u8::MAX.into(),
            Codes::Narrow(_) => u16::MAX.into(),
            Codes::Wide(_) => u32::MAX,
        }
    }

    /// The stream in the narrowest width that holds `max` (never narrower than now), written
    /// anew at `placement` when it must widen.
    pub(crate) fn widened(self, max: u32, placement: Placement) -> std::io::Result<Codes> {
        if max <= self.capacity_max() {
            return Ok(self);
        }
        let mut wide = CodesWriter::of_width(placement, max)?;
        wide.copy_from(&self, max)?;
        wide.finish()
    }

    /// Where the stream lives.
    fn placement(&self) -> Placement {
        if with_codes!(self, c => c.is_mapped()) {
            Placement::TempFile
        } else {
            Placement::Memory
        }
    }

    /// Hands the resident pages of codes `range` back (see [`Stream::release`]).
    fn release(&self, range: std::ops::Range<usize>) {
        with_codes!(self, c => c.release(range))
    }
}

/// Hands back the resident pages of the records of slots `slots` in a layout's streams
/// (offsets, local tables, codes, weights; see [`Stream::release`]); a no-op in memory.
pub(crate) fn release_records(
    (offsets, locals, codes, weights): (&Stream<SplitOffsets>, &Stream<u32>, &Codes, &Stream<f32>),
    slots: std::ops::Range<usize>,
) {
    if !weights.is_mapped() || slots.is_empty() {
        return;
    }
    let (o, end) = (offsets[slots.start], offsets[slots.end]);
    locals.release(o.locals..end.locals);
    codes.release(o.codes..end.codes);
    weights.release(o.weights..end.weights);
    offsets.release(slots);
}

impl CodesWriter {
    /// An empty 8-bit stream at `placement` with room for `capacity` codes.
    pub(crate) fn new(placement: Placement, capacity: usize) -> std::io::Result<CodesWriter> {
        Ok(CodesWriter::Byte(Writer::new(placement, capacity)?))
    }

    /// Number of codes.
    pub(crate) fn len(&self) -> usize {
        match self {
            CodesWriter::Byte(c) => c.len(),
            CodesWriter::Narrow(c) => c.len(),
            CodesWriter::Wide(c) => c.len(),
        }
    }

    /// Largest code the current width holds.
    fn capacity_max(&self) -> u32 {
        match self {
            CodesWriter::Byte(_) => u8::MAX.into(),
            CodesWriter::Narrow(_) => u16::MAX.into(),
            CodesWriter::Wide(_) => u32::MAX,
        }
    }

    /// An empty stream at `placement` in the narrowest width that holds `max`.
    fn of_width(placement: Placement, max: u32) -> std::io::Result<CodesWriter> {
        Ok(if max <= u8::MAX.into() {
            CodesWriter::Byte(Writer::new(placement, 0)?)
        } else if max <= u16::MAX.into() {
            CodesWriter::Narrow(Writer::new(placement, 0)?)
        } else {
            CodesWriter::Wide(Writer::new(placement, 0)?)
        })
    }

    /// Appends all of `codes`, whose largest code is `max`, a slice at a time (a stream in a
    /// file is never read into memory whole).
    fn copy_from(&mut self, codes: &Codes, max: u32) -> std::io::Result<()> {
        use frames::LocalIndex;
        const SLICE: usize = 1 << 16;
        let mut wide: Vec<u32> = Vec::with_capacity(SLICE);
        with_codes!(codes, c => {
            for (i, slice) in c.chunks(SLICE).enumerate() {
                wide.clear();
                // Codes fit in u32 (they were recorded from u32 values).
                wide.extend(slice.iter().map(|&x| x.at() as u32));
                self.extend_widening(&wide, max)?;
                c.release(i * SLICE..(i + 1) * SLICE);
            }
        });
        Ok(())
    }

    /// Rewrites the stream in the narrowest width that holds `max` (never narrower than now),
    /// at the same placement.
    fn widen_to(&mut self, max: u32) -> std::io::Result<()> {
        if max <= self.capacity_max() {
            return Ok(());
        }
        let placeholder = CodesWriter::Byte(Writer::new(Placement::Memory, 0)?);
        let old = std::mem::replace(self, placeholder).finish()?;
        let mut wide = CodesWriter::of_width(old.placement(), max)?;
        wide.copy_from(&old, max)?;
        *self = wide;
        Ok(())
    }

    /// Appends `src`, whose largest code is `max`, widening the stream first if needed.
    pub(crate) fn extend_widening(&mut self, src: &[u32], max: u32) -> std::io::Result<()> {
        self.widen_to(max)?;
        match self {
            // `max` fits the width (widened above), so the casts keep every value.
            CodesWriter::Byte(c) => src.iter().try_for_each(|&x| c.push(x as u8)),
            CodesWriter::Narrow(c) => src.iter().try_for_each(|&x| c.push(x as u16)),
            CodesWriter::Wide(c) => c.extend_from_slice(src),
        }
    }

    /// The finished stream.
    pub(crate) fn finish(self) -> std::io::Result<Codes> {
        Ok(match self {
            CodesWriter::Byte(c) => Codes::Byte(c.finish()?),
            CodesWriter::Narrow(c) => Codes::Narrow(c.finish()?),
            CodesWriter::Wide(c) => Codes::Wide(c.finish()?),
        })
    }
}

impl DetailPyramid {
    /// Number of vertices of the coarsest level, `n0`.
    pub fn n_base_vertices(&self) -> usize {
        self.n_base
    }

    /// Number of vertices of the finest level (vertices referenced by a face).
    pub fn n_vertices(&self) -> usize {
        self.n_finest
    }

    /// Length of the signals [`DetailPyramid::synthesize`] returns: the finest level plus the vertices
    /// no face refers to (which pass through unchanged).
    pub fn signal_len(&self) -> usize {
        self.n_finest + self.passthrough.len()
    }

    /// Number of vertex splits (`n_vertices() − n_base_vertices()`).
    pub fn n_splits(&self) -> usize {
        self.offsets.len().saturating_sub(1)
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

    /// Storage slot of split `k` (split `k` creates vertex `n0 + k`, level `n0 + k + 1`): the
    /// pyramid stores splits wave by wave, each wave a set of splits synthesis can run at once.
    #[inline]
    pub fn split_slot(&self, k: usize) -> usize {
        self.waves.slot_of(k)
    }

    /// The level (vertex count) whose details split `k` carries.
    #[inline]
    pub(crate) fn level_of_split(&self, k: usize) -> usize {
        self.n_base + k + 1
    }

    /// The vertices whose values split `k` sets (the new vertex first, then its 1-ring) and
    /// their details in local frames `(t1, t2, n)`.
    pub fn split_details(
        &self,
        k: usize,
    ) -> (&[u32], impl ExactSizeIterator<Item = DVec3> + Clone + '_) {
        let slot = self.split_slot(k);
        let (o, next) = (self.offsets[slot], self.offsets[slot + 1]);
        let t = next.details - o.details;
        let step = self.detail_step;
        (
            &self.locals[o.locals..o.locals + t],
            self.details[o.details..next.details]
                .iter()
                .map(move |&q| quantise::dequantised(q, step)),
        )
    }

    /// The details of split `k` as the pyramid keeps them: whole multiples of
    /// [`Self::detail_step`], in the order of [`Self::split_details`].
    pub(crate) fn split_quantised(&self, k: usize) -> &[[i32; 3]] {
        let slot = self.split_slot(k);
        &self.details[self.offsets[slot].details..self.offsets[slot + 1].details]
    }

    /// Whether the signal-independent layout (weights, local tables, codes: most of a large
    /// pyramid) lives in a temporary file mapped into memory rather than on the heap; decided
    /// by its size and `MESHPYR_SPILL_MIB` (docs/performance.md, "Scans of millions of
    /// vertices"). Results are the same bits either way.
    pub fn layout_in_file(&self) -> bool {
        self.weights.is_mapped()
    }

    /// Hands back the resident pages of the layout records of slots `slots` (a pass is done
    /// with them; see [`Stream::release`]).
    pub(crate) fn release_slots(&self, slots: std::ops::Range<usize>) {
        release_records(
            (&self.offsets, &self.locals, &self.codes, &self.weights),
            slots,
        );
    }

    /// The step every detail component is a whole multiple of (a power of two near 2^-21 of
    /// the signal's bounding-box diagonal): unit gains reproduce the analysed signal within
    /// `√3/2` of it.
    pub fn detail_step(&self) -> f64 {
        self.detail_step
    }

    /// Size of the pyramid in bytes (weights, indices, fans, details, base signal), counting
    /// the layout a large pyramid keeps in a temporary file ([`Self::layout_in_file`]).
    pub fn memory_bytes(&self) -> usize {
        self.offsets.bytes()
            + self.locals.bytes()
            + self.codes.bytes()
            + self.weights.bytes()
            + 12 * self.details.len()
            + 24 * (self.base.len() + self.passthrough.len())
            + self.waves.memory_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::pm::{PmOptions, ProgressiveMesh};
    use crate::progress::NoProgress;
    use crate::relax::SecondDifference;

    /// How far unit gains may land from the analysed signal: `√3/2` of a detail step (the
    /// closed loop's bound, docs/algorithms.md §1f), plus rounding.
    fn closed_loop_bound(p: &DetailPyramid) -> f64 {
        0.5 * 3f64.sqrt() * p.detail_step() + 1e-12 * p.bbox_diagonal()
    }

    #[test]
    fn codes_of_every_width_synthesize_the_same_bits() {
        // Large neighbourhoods need 16- or 32-bit local indices; every width must run the same
        // arithmetic. Widen a small pyramid's 8-bit codes and compare bits.
        let (p, t) = crate::mesh::shapes::torus(12, 10, |u, v| {
            let r = 2.0 + (1.0 + 0.1 * (3.0 * u).sin()) * v.cos();
            DVec3::new(r * u.cos(), r * u.sin(), v.sin())
        });
        let mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
        let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
        let narrow =
            DetailPyramid::analyze(&pm, &SecondDifference::default(), &NoProgress).unwrap();
        let Codes::Byte(c) = &narrow.codes else {
            panic!("a small mesh should get 8-bit codes");
        };
        let mut wide = narrow.clone();
        wide.codes = Codes::Wide(c.iter().map(|&x| x as u32).collect::<Vec<_>>().into());
        let mut middle = narrow.clone();
        middle.codes = Codes::Narrow(c.iter().map(|&x| x as u16).collect::<Vec<_>>().into());
        assert_eq!(
            middle.synthesize(&LevelGains::unit()),
            wide.synthesize(&LevelGains::unit())
        );
        let gains = gains::Filter::default()
            .gain(LevelSpec::Vertices(20), LevelSpec::Vertices(60), 1.7)
            .resolve(1.0);
        let (a, b) = (narrow.synthesize(&gains), wide.synthesize(&gains));
        assert_eq!(a, b);
        assert!(wide.memory_bytes() > narrow.memory_bytes());
        let err = narrow
            .synthesize(&LevelGains::unit())
            .iter()
            .zip(pm.original_positions())
            .map(|(x, y)| (*x - *y).length())
            .fold(0.0, f64::max);
        assert!(err <= closed_loop_bound(&narrow), "{err:e}");
    }

    /// Two components: a double cone whose two apexes join all of 300 rim vertices, and a
    /// bumpy torus. The rim vertices collapse first (at the finest levels the apexes' fans
    /// need 16-bit codes), the torus later (8-bit codes), so on two threads the two ranges
    /// are recorded in different widths and joined; the pyramid must be the one-thread
    /// pyramid, bit for bit.
    #[test]
    fn ranges_recorded_in_different_code_widths_join_exactly() {
        let rim = 300u32;
        let mut p = vec![DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.0, -1.0)];
        let mut t = Vec::new();
        for k in 0..rim {
            let a = k as f64 / rim as f64 * std::f64::consts::TAU;
            p.push(DVec3::new(a.cos(), a.sin(), 0.0));
            let (b, c) = (2 + k, 2 + (k + 1) % rim);
            t.push([0, b, c]);
            t.push([1, c, b]);
        }
        let (torus_p, torus_t) = crate::mesh::shapes::torus(60, 40, |u, v| {
            let r = 2.0 + (1.0 + 0.2 * (5.0 * u).sin() * (3.0 * v).cos()) * v.cos();
            DVec3::new(10.0 + r * u.cos(), r * u.sin(), v.sin())
        });
        let first = p.len() as u32;
        p.extend(torus_p);
        t.extend(torus_t.iter().map(|f| f.map(|x| first + x)));
        let mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
        let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| DetailPyramid::analyze(&pm, &SecondDifference::default(), &NoProgress))
                .unwrap()
        };
        let (one, two) = (on(1), on(2));
        assert!(
            matches!(one.codes, Codes::Narrow(_)),
            "the apex needs 16-bit codes"
        );
        let codes = |p: &DetailPyramid| with_codes!(&p.codes, c => c.iter().map(|&x| frames::LocalIndex::at(x)).collect::<Vec<usize>>());
        assert_eq!(codes(&one), codes(&two));
        assert_eq!(*one.locals, *two.locals);
        assert_eq!(*one.offsets, *two.offsets);
        assert_eq!(one.details, two.details);
        assert_eq!(
            one.weights.iter().map(|w| w.to_bits()).collect::<Vec<_>>(),
            two.weights.iter().map(|w| w.to_bits()).collect::<Vec<_>>()
        );
        let unit = two.synthesize(&LevelGains::unit());
        let err = unit
            .iter()
            .zip(pm.original_positions())
            .map(|(x, y)| (*x - *y).length())
            .fold(0.0, f64::max);
        assert!(err <= closed_loop_bound(&two), "{err:e}");
    }

    /// A layout in a temporary file is the layout in memory: same streams, same details, same
    /// synthesis bits, on any thread count (the ranges are recorded into separate files and
    /// gathered into slot order batch by batch). Scans above the threshold take this path; the
    /// test meshes are below it, so it is forced here.
    #[test]
    fn a_layout_in_a_temporary_file_synthesizes_the_bits_of_one_in_memory() {
        let (p, t) = crate::mesh::shapes::torus(90, 60, |u, v| {
            let r = 2.0 + (1.0 + 0.15 * (5.0 * u).sin() * (3.0 * v).cos()) * v.cos();
            DVec3::new(r * u.cos(), r * u.sin(), v.sin())
        });
        let mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
        let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
        let signal = pm.original_positions();
        let relax = SecondDifference::default();
        let at = |placement: Placement, threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    DetailPyramid::analyze_signal_at(
                        &pm,
                        &relax,
                        signal,
                        &NoProgress,
                        Some(placement),
                    )
                })
                .unwrap()
        };
        let memory = at(Placement::Memory, 1);
        assert!(!memory.layout_in_file());
        let gains = gains::Filter::default()
            .gain(LevelSpec::Vertices(200), LevelSpec::Vertices(2000), 2.5)
            .resolve(memory.surface_area());
        let expected = memory.synthesize(&gains);
        for threads in [1, 2, 3] {
            let file = at(Placement::TempFile, threads);
            assert!(file.layout_in_file());
            assert_eq!(*file.offsets, *memory.offsets);
            assert_eq!(*file.locals, *memory.locals);
            let codes = |p: &DetailPyramid| with_codes!(&p.codes, c => c.iter().map(|&x| frames::LocalIndex::at(x)).collect::<Vec<usize>>());
            assert_eq!(codes(&file), codes(&memory));
            let bits =
                |p: &DetailPyramid| p.weights.iter().map(|w| w.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&file), bits(&memory));
            assert_eq!(file.details, memory.details);
            assert_eq!(file.synthesize(&gains), expected, "{threads} threads");
            // A clone shares the mapping and reads the same.
            assert_eq!(file.clone().synthesize(&gains), expected);
        }
    }
}
