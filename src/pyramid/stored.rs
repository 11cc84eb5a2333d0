//! A pyramid whose details come from a `.pyr` file's `DETL` section (the codec's record
//! [`StoredDetails`]): synthesis still needs the relaxation weights and fans (step 1 of the
//! analysis, [`Layout::record`]), but not the detail passes (steps 2–5), and the spectrum needs
//! neither.

use super::analysis::{Layout, surface_stats};
use super::quantise::dequantised;
use super::spectrum::octave_spectrum;
use super::{DetailPyramid, PyramidError, Spectrum};
use crate::format::StoredDetails;
use crate::pm::ProgressiveMesh;
use crate::progress::Progress;
use crate::relax::RelaxationSpec;

impl StoredDetails {
    /// The details of `pyramid`, analysed with `relaxation`, in split order, with the step
    /// they are whole multiples of (what a `.pyr` file stores; the pyramid's own values, so
    /// a pyramid opened from them filters with the very same bits), coded as the file codes
    /// them ([`StoredDetails::coded`]).
    pub fn of(pyramid: &DetailPyramid, relaxation: RelaxationSpec) -> StoredDetails {
        StoredDetails::coded(
            relaxation,
            pyramid.base.clone(),
            pyramid.n_splits(),
            |k| pyramid.split_quantised(k),
            pyramid.detail_step,
        )
        .expect("a pyramid's step is a power of two")
    }

    /// The detail spectrum of these details on the hierarchy `pm`, without any analysis.
    pub fn spectrum(&self, pm: &ProgressiveMesh) -> Result<Spectrum, PyramidError> {
        self.check_counts_sum(pm)?;
        let n_finest = pm.n_vertices();
        let (area, diagonal) =
            surface_stats(&pm.original_positions()[..n_finest], pm.finest_faces());
        let details = self.quantised().map_err(|e| mismatch(e.to_string()))?;
        let step = self.step;
        let mut at = 0;
        let per_split = self.counts.iter().map(|&c| {
            let d = details[at..at + c as usize]
                .iter()
                .map(move |&q| dequantised(q, step));
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
            || total != self.n_details() as u64
            || self.base.len() != pm.n_base_vertices()
        {
            return Err(mismatch(format!(
                "{} splits, {} details and {} base values for a hierarchy of {} splits and {} base vertices",
                self.counts.len(),
                self.n_details(),
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
        Self::with_stored_prefix(pm, relaxation, stored, pm.splits().len(), progress)
    }

    /// [`Self::with_stored_details`] up to level `level` only (at least the base level, at
    /// most the finest): the pyramid of the levels up to it, as if the hierarchy ended there,
    /// with the whole hierarchy's surface area and diagonal. Its synthesis up to `level` gives
    /// the bits of the whole pyramid's, and costs the splits up to `level` only (what a
    /// viewer needs before the rest is recorded).
    pub fn with_stored_details_up_to(
        pm: &ProgressiveMesh,
        relaxation: &dyn crate::relax::Relaxation,
        stored: &StoredDetails,
        level: usize,
        progress: &dyn Progress,
    ) -> Result<DetailPyramid, PyramidError> {
        let n_splits = level.saturating_sub(pm.n_base_vertices());
        Self::with_stored_prefix(pm, relaxation, stored, n_splits, progress)
    }

    /// The pyramid of the first `n_splits` splits with their stored details.
    fn with_stored_prefix(
        pm: &ProgressiveMesh,
        relaxation: &dyn crate::relax::Relaxation,
        stored: &StoredDetails,
        n_splits: usize,
        progress: &dyn Progress,
    ) -> Result<DetailPyramid, PyramidError> {
        stored.check_counts_sum(pm)?;
        let n_splits = n_splits.min(pm.splits().len());
        let layout = Layout::record_prefix(pm, relaxation, progress, None, n_splits)?;
        let expected: usize = stored.counts[..n_splits].iter().map(|&c| c as usize).sum();
        if layout.n_details() != expected {
            return Err(mismatch(format!(
                "{expected} details where the hierarchy has {}",
                layout.n_details()
            )));
        }
        let mut details = vec![[0; 3]; expected];
        let mut mismatched = None;
        stored
            .for_each_block_up_to(n_splits, |first, counts, block| {
                let mut at = 0;
                for (k, &c) in (first..n_splits).zip(counts) {
                    let c = c as usize;
                    if layout.details_of_split(k) != c {
                        mismatched.get_or_insert(k);
                    } else if mismatched.is_none() {
                        let to = layout.details_start(k);
                        details[to..to + c].copy_from_slice(&block[at..at + c]);
                    }
                    at += c;
                }
            })
            .map_err(|e| mismatch(e.to_string()))?;
        if let Some(k) = mismatched {
            return Err(mismatch(format!(
                "split {k} carries {} details where its level has {}",
                stored.counts[k],
                layout.details_of_split(k)
            )));
        }
        progress.update(1.0);
        // A prefix's pyramid passes no vertex through: it ends at its last split's level.
        let positions = pm.original_positions();
        let signal = if n_splits == pm.splits().len() {
            positions
        } else {
            &positions[..layout.n_finest]
        };
        let pyramid = layout.into_pyramid(
            relaxation,
            signal,
            stored.base.clone(),
            details,
            stored.step,
        );
        Ok(pyramid)
    }
}
