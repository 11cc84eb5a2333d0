//! A pyramid whose details come from a `.pyr` file's `DETL` section: synthesis still needs the
//! relaxation weights and fans (step 1 of the analysis, [`Layout::record`]), but not the
//! detail pass (steps 2–5), and the spectrum needs neither.

use super::analysis::{Layout, surface_stats};
use super::spectrum::octave_spectrum;
use super::{DetailPyramid, LevelGains, PyramidError, Spectrum};
use crate::pm::ProgressiveMesh;
use crate::progress::Progress;
use crate::relax::RelaxationSpec;
use glam::DVec3;

/// The details of a pyramid in split order, as a `.pyr` file stores them (`formats/pyr.md`,
/// section `DETL`), with what they were computed with.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredDetails {
    /// The relaxation operator, with its options, the details were analysed with.
    pub relaxation: RelaxationSpec,
    /// The base signal `f^(n0)` (exact).
    pub base: Vec<DVec3>,
    /// Per split, how many details it carries (the new vertex and its ring).
    pub counts: Vec<u32>,
    /// All details in split order, each in its local frame `(t1, t2, n)`.
    pub details: Vec<DVec3>,
    /// The quantisation step of every detail component (model units; 0 for exact values):
    /// each component is within half of it of the analysed one.
    pub step: f64,
}

impl StoredDetails {
    /// The details of `pyramid`, analysed with `relaxation`, in split order (exact: `step` 0).
    pub fn of(pyramid: &DetailPyramid, relaxation: RelaxationSpec) -> StoredDetails {
        let n = pyramid.n_splits();
        let mut counts = Vec::with_capacity(n);
        let mut details = Vec::with_capacity(pyramid.n_details());
        for k in 0..n {
            let (_, d) = pyramid.split_details(k);
            counts.push(d.len() as u32);
            details.extend_from_slice(d);
        }
        StoredDetails {
            relaxation,
            base: pyramid.base.clone(),
            counts,
            details,
            step: 0.0,
        }
    }

    /// The details of `pyramid` (analysed with `relaxation`) quantised for a `.pyr` file: each
    /// component rounded to a multiple of a power-of-two step, the coarsest from 2^-36 of the
    /// bounding-box diagonal down to 2^-52 for which synthesis from the rounded details stays
    /// within 2.5e-10 of the diagonal of synthesis from the exact ones (a quarter of the 1e-9
    /// promised for any filter), both with unit gains and with every level's gain 2 (a
    /// fine-band enhancement shows the largest errors; near-degenerate triangles, whose frames
    /// turn with small changes, need the finer steps). Details read from a file keep their
    /// step.
    pub fn quantised(pyramid: &DetailPyramid, relaxation: RelaxationSpec) -> StoredDetails {
        if pyramid.detail_step > 0.0 {
            return StoredDetails {
                step: pyramid.detail_step,
                ..StoredDetails::of(pyramid, relaxation)
            };
        }
        let diagonal = pyramid.bbox_diagonal;
        let top = if diagonal > 0.0 && diagonal.is_finite() {
            diagonal.log2().floor() as i32
        } else {
            0
        };
        let doubled = LevelGains {
            bands: vec![(0, usize::MAX, 2.0)],
            normal_only: false,
        };
        let gains = [LevelGains::unit(), doubled];
        let exact: Vec<Vec<DVec3>> = gains.iter().map(|g| pyramid.synthesize(g)).collect();
        let mut bits = FIRST_STEP_BITS;
        loop {
            let step = 2f64.powi(top - bits);
            let rounded: Vec<DVec3> = pyramid
                .details
                .iter()
                .map(|d| (*d / step).round() * step)
                .collect();
            let within = |(g, e): (&LevelGains, &Vec<DVec3>)| {
                let synthesized = pyramid.synthesize_with_details(g, &rounded);
                max_distance(&synthesized, e) <= QUANTISATION_CHECK * diagonal
            };
            if bits >= LAST_STEP_BITS || gains.iter().zip(&exact).all(within) {
                let mut stored = StoredDetails::of(pyramid, relaxation);
                stored.step = step;
                let mut at = 0;
                for k in 0..pyramid.n_splits() {
                    let from = pyramid.offsets[pyramid.split_slot(k)].details;
                    let n = stored.counts[k] as usize;
                    stored.details[at..at + n].copy_from_slice(&rounded[from..from + n]);
                    at += n;
                }
                return stored;
            }
            bits += 2;
        }
    }

    /// The detail spectrum of these details on the hierarchy `pm`, without any analysis.
    pub fn spectrum(&self, pm: &ProgressiveMesh) -> Result<Spectrum, PyramidError> {
        self.check_counts_sum(pm)?;
        let n_finest = pm.n_vertices();
        let (area, diagonal) =
            surface_stats(&pm.original_positions()[..n_finest], pm.finest_faces());
        let mut at = 0;
        let per_split = self.counts.iter().map(|&c| {
            let d = &self.details[at..at + c as usize];
            at += c as usize;
            d
        });
        Ok(octave_spectrum(
            pm.n_base_vertices(),
            n_finest,
            area,
            diagonal,
            per_split,
        ))
    }

    /// The counts must cover the hierarchy's splits and the details exactly.
    fn check_counts_sum(&self, pm: &ProgressiveMesh) -> Result<(), PyramidError> {
        let total: u64 = self.counts.iter().map(|&c| u64::from(c)).sum();
        if self.counts.len() != pm.splits().len()
            || total != self.details.len() as u64
            || self.base.len() != pm.n_base_vertices()
        {
            return Err(mismatch(format!(
                "{} splits, {} details and {} base values for a hierarchy of {} splits and {} base vertices",
                self.counts.len(),
                self.details.len(),
                self.base.len(),
                pm.splits().len(),
                pm.n_base_vertices()
            )));
        }
        Ok(())
    }
}

/// The largest synthesis error, relative to the diagonal, that [`StoredDetails::quantised`]
/// accepts: a quarter of the 1e-9 the stored details promise for any filter.
const QUANTISATION_CHECK: f64 = 2.5e-10;

/// The coarsest step [`StoredDetails::quantised`] tries, in bits below the diagonal.
const FIRST_STEP_BITS: i32 = 36;

/// The finest: 2^-52 of the diagonal is the rounding of the positions themselves.
const LAST_STEP_BITS: i32 = 52;

fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length())
        .fold(0.0, f64::max)
}

fn mismatch(what: String) -> PyramidError {
    PyramidError::Invalid(format!(
        "the stored details do not match the hierarchy: {what}"
    ))
}

impl DetailPyramid {
    /// The pyramid of `pm`'s original positions with `stored` details: only the relaxation
    /// weights and fans are computed (with `relaxation`, which must be the operator `stored`
    /// was analysed with). Details that do not fit the hierarchy (another split's ring size)
    /// are an error.
    pub fn with_stored_details(
        pm: &ProgressiveMesh,
        relaxation: &dyn crate::relax::Relaxation,
        stored: &StoredDetails,
        progress: &dyn Progress,
    ) -> Result<DetailPyramid, PyramidError> {
        stored.check_counts_sum(pm)?;
        let layout = Layout::record(pm, relaxation, progress)?;
        if layout.n_details() != stored.details.len() {
            return Err(mismatch(format!(
                "{} details where the hierarchy has {}",
                stored.details.len(),
                layout.n_details()
            )));
        }
        let mut details = vec![DVec3::ZERO; stored.details.len()];
        let mut at = 0;
        for (k, &c) in stored.counts.iter().enumerate() {
            let c = c as usize;
            if layout.details_of_split(k) != c {
                return Err(mismatch(format!(
                    "split {k} carries {c} details where its level has {}",
                    layout.details_of_split(k)
                )));
            }
            let to = layout.details_start(k);
            details[to..to + c].copy_from_slice(&stored.details[at..at + c]);
            at += c;
        }
        progress.update(1.0);
        let mut pyramid = layout.into_pyramid(
            relaxation,
            pm.original_positions(),
            stored.base.clone(),
            details,
        );
        pyramid.detail_step = stored.step;
        Ok(pyramid)
    }
}
