//! A pyramid whose details come from a `.pyr` file's `DETL` section (the codec's record
//! [`StoredDetails`]): synthesis still needs the relaxation weights and fans (step 1 of the
//! analysis, [`Layout::record`]), but not the detail passes (steps 2–5), and the spectrum needs
//! neither.

use super::analysis::{Layout, surface_stats};
use super::quantise::dequantised;
use super::spectrum::{octave_bands, octave_spectrum, octave_spectrum_of_sums};
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
        let (area, diagonal) = surface_stats(
            &pm.original_positions()[..pm.n_vertices()],
            pm.finest_faces(),
        );
        self.spectrum_on(pm, area, diagonal)
    }

    /// [`Self::spectrum`] on a finest mesh of area `area` and bounding-box diagonal
    /// `diagonal` (`surface_stats` of `pm`'s, which a caller may hold already).
    pub(crate) fn spectrum_on(
        &self,
        pm: &ProgressiveMesh,
        area: f64,
        diagonal: f64,
    ) -> Result<Spectrum, PyramidError> {
        self.check_counts_sum(pm)?;
        let (n_base, n_finest) = (pm.n_base_vertices(), pm.n_vertices());
        match self.exact_band_sums(n_base, n_finest) {
            Some(sums) => Ok(octave_spectrum_of_sums(
                n_base,
                n_finest,
                area,
                diagonal,
                &self.counts,
                &sums,
            )),
            None => self.summed_spectrum(n_base, n_finest, area, diagonal),
        }
    }

    /// The spectrum from the decoded details, summed one by one.
    fn summed_spectrum(
        &self,
        n_base: usize,
        n_finest: usize,
        area: f64,
        diagonal: f64,
    ) -> Result<Spectrum, PyramidError> {
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
        Ok(octave_spectrum(n_base, n_finest, area, diagonal, per_split))
    }

    /// Each band's `Σ |d|²` from the details' squares per octave, when that is exactly what
    /// summing the dequantised details one by one in `f64` gives: every component is `q · step`
    /// with a power-of-two step, so each `|d|²` and each partial sum is a whole multiple of
    /// `step²` and exact while the band's `Σ q·q` stays below 2^53 and `step²` is a normal
    /// number. `None` otherwise (the caller then sums the decoded details).
    fn exact_band_sums(&self, n_base: usize, n_finest: usize) -> Option<Vec<f64>> {
        const EXACT: u128 = 1 << f64::MANTISSA_DIGITS;
        let step2 = self.step * self.step;
        if !step2.is_normal() || self.base.len() != n_base {
            return None;
        }
        let squares = self.octave_squares();
        let mut entries = squares.iter().peekable();
        let mut sums = Vec::new();
        for (_, hi) in octave_bands(n_base, n_finest) {
            let mut total = 0u128;
            while let Some(&&(key, s)) = entries.peek() {
                if key.min(n_finest) != hi {
                    break;
                }
                total = total.saturating_add(s);
                entries.next();
            }
            let sum = (total < EXACT).then_some(total as f64 * step2)?;
            sums.push(sum.is_finite().then_some(sum)?);
        }
        entries.next().is_none().then_some(sums)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Details with components spread over the `i32` range's low and high ends, so that some
    /// octaves' sums are exact and, with `big`, some are not.
    fn details(n_base: usize, n_splits: usize, big: i32, step: f64) -> StoredDetails {
        let counts: Vec<u32> = (0..n_splits as u32).map(|k| 5 + k % 4).collect();
        let n: usize = counts.iter().map(|&c| c as usize).sum();
        let mut x = 0x9e37_79b9_u32;
        let quantised = (0..n)
            .map(|i| {
                [0, 1, 2].map(|_| {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    let small = (x % 2001) as i32 - 1000;
                    if i % 97 == 0 {
                        big.saturating_mul(small.signum())
                    } else {
                        small
                    }
                })
            })
            .collect();
        let base = vec![glam::DVec3::ZERO; n_base];
        StoredDetails::from_quantised(RelaxationSpec::default(), base, counts, quantised, step)
            .unwrap()
    }

    fn split_of(all: &[[i32; 3]], start: usize, count: u32) -> &[[i32; 3]] {
        &all[start..start + count as usize]
    }

    #[test]
    fn the_spectrum_from_octave_squares_has_the_bits_of_the_summed_details() {
        for (n_base, n_splits, big, step) in [
            (4, 9000, 1 << 20, 0.25),
            (100, 20_000, 1 << 18, 2f64.powi(-30)),
            (7, 3, 1000, 1.0),
            (10, 0, 1, 1.0),
        ] {
            let quantised = details(n_base, n_splits, big, step);
            let all: &[[i32; 3]] = match quantised.quantised().unwrap() {
                std::borrow::Cow::Borrowed(q) => q,
                std::borrow::Cow::Owned(_) => unreachable!("held quantised"),
            };
            let starts: Vec<usize> = quantised
                .counts
                .iter()
                .scan(0, |at, &c| {
                    *at += c as usize;
                    Some(*at - c as usize)
                })
                .collect();
            let counts = &quantised.counts;
            let split = |k: usize| split_of(all, starts[k], counts[k]);
            let coded = StoredDetails::coded(
                quantised.relaxation,
                quantised.base.clone(),
                n_splits,
                split,
                step,
            )
            .unwrap();
            let n_finest = n_base + n_splits;
            for held in [&quantised, &coded] {
                let sums = held.exact_band_sums(n_base, n_finest).expect("exact sums");
                let fast = octave_spectrum_of_sums(n_base, n_finest, 2.5, 3.0, &held.counts, &sums);
                let summed = held.summed_spectrum(n_base, n_finest, 2.5, 3.0).unwrap();
                assert_eq!(fast.to_csv(), summed.to_csv(), "{n_base} {n_splits}");
                assert_eq!(fast, summed);
            }
        }
    }

    #[test]
    fn octave_sums_beyond_the_exact_range_are_summed_from_the_details() {
        let held = details(4, 5000, i32::MAX, 1.0);
        assert!(held.exact_band_sums(4, 5004).is_none());
        // A step whose square is subnormal is not exact either.
        let tiny = details(4, 50, 1, 2f64.powi(-540));
        assert!(tiny.exact_band_sums(4, 54).is_none());
    }
}
