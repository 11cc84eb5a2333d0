//! A pyramid whose details come from a `.pyr` file's `DETL` section (the codec's record
//! [`StoredDetails`]): synthesis still needs the relaxation weights and fans (step 1 of the
//! analysis, [`Layout::record`]), but not the detail passes (steps 2–5), and the spectrum needs
//! neither.

use super::analysis::{Layout, surface_stats};
use super::quantise::{dequantised, quantised};
use super::spectrum::octave_spectrum;
use super::{DetailPyramid, PyramidError, Spectrum};
use crate::format::StoredDetails;
use crate::pm::ProgressiveMesh;
use crate::progress::Progress;
use crate::relax::RelaxationSpec;

impl StoredDetails {
    /// The details of `pyramid`, analysed with `relaxation`, in split order, with the step
    /// they are whole multiples of (what a `.pyr` file stores; the pyramid's own values, so
    /// a pyramid opened from them filters with the very same bits).
    pub fn of(pyramid: &DetailPyramid, relaxation: RelaxationSpec) -> StoredDetails {
        let n = pyramid.n_splits();
        let mut counts = Vec::with_capacity(n);
        let mut details = Vec::with_capacity(pyramid.n_details());
        for k in 0..n {
            let (_, d) = pyramid.split_details(k);
            counts.push(d.len() as u32);
            details.extend(d);
        }
        StoredDetails {
            relaxation,
            base: pyramid.base.clone(),
            counts,
            details,
            step: pyramid.detail_step,
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
            let d = self.details[at..at + c as usize].iter().copied();
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
        let layout = Layout::record(pm, relaxation, progress, None)?;
        if layout.n_details() != stored.details.len() {
            return Err(mismatch(format!(
                "{} details where the hierarchy has {}",
                stored.details.len(),
                layout.n_details()
            )));
        }
        let step = stored.step;
        if !(step > 0.0 && step.log2().fract() == 0.0) {
            return Err(mismatch(format!(
                "a detail step of {step} (the steps are powers of two)"
            )));
        }
        let mut details = vec![[0; 3]; stored.details.len()];
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
            for (q, &d) in details[to..to + c]
                .iter_mut()
                .zip(&stored.details[at..at + c])
            {
                *q = quantised(d, step);
                if dequantised(*q, step) != d {
                    return Err(mismatch(format!(
                        "split {k} has a detail that is not a whole multiple of the step {step} in 32 bits"
                    )));
                }
            }
            at += c;
        }
        progress.update(1.0);
        let pyramid = layout.into_pyramid(
            relaxation,
            pm.original_positions(),
            stored.base.clone(),
            details,
            step,
        );
        Ok(pyramid)
    }
}
