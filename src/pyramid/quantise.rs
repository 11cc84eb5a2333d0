//! Details as integers: every detail component is a whole multiple of one power-of-two step,
//! held as an `i32` (12 bytes per detail instead of 24) and written to `.pyr` files as it is.
//!
//! The step alone would not bound the error: synthesis builds each level's frames and
//! predictions from the level below, so a rounding at a coarse level moves everything
//! predicted from it, and near-degenerate frames amplify that (up to four orders of magnitude
//! on real scans). So the analysis quantises in a closed loop (`docs/algorithms.md` §1f): it
//! first records, for every split, the values its touched vertices must reach (the analysed
//! `f^(n)` there), then runs the synthesis with unit gains and quantises each split's details
//! against the values synthesis actually predicts. Every touched vertex thus lands within half
//! a step per frame axis of its target, whatever happened below it, and since the last split
//! that touches a vertex targets its input value, unit gains reproduce the input within
//! `√3/2 · step`.

use glam::DVec3;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// Bits of the step below the signal's bounding-box diagonal: the step is
/// `2^(⌊log2 diagonal⌋ − DETAIL_STEP_BITS)`, at most 2^-21 of the diagonal, so unit gains
/// reproduce the input within `√3/2 · 2^-21 ≈ 4.1e-7` of it (the promise is 1e-6).
pub(crate) const DETAIL_STEP_BITS: i32 = 21;

/// The detail step for a signal whose bounding box has diagonal `diagonal` (a power of two; a
/// signal with no extent, or a non-finite one, gets 2^-21).
pub(crate) fn detail_step(diagonal: f64) -> f64 {
    let top = if diagonal > 0.0 && diagonal.is_finite() {
        diagonal.log2().floor() as i32
    } else {
        0
    };
    // Normal powers of two only, so that `q · step` stays exact for every `i32` q.
    2f64.powi((top - DETAIL_STEP_BITS).clamp(-990, 960))
}

/// `d` in whole steps, rounded to nearest; components beyond the `i32` range saturate (a
/// detail over 2^31 steps, a thousand diagonals, only comes from a broken prediction; the
/// closed loop repairs its vertex at the next split that touches it).
#[inline]
pub(crate) fn quantised(d: DVec3, step: f64) -> [i32; 3] {
    d.to_array().map(|x| (x / step).round() as i32)
}

/// The detail `q` steps long (exact: a power-of-two step times an `i32`).
#[inline(always)]
pub(crate) fn dequantised(q: [i32; 3], step: f64) -> DVec3 {
    DVec3::new(
        f64::from(q[0]) * step,
        f64::from(q[1]) * step,
        f64::from(q[2]) * step,
    )
}

/// The bounding-box diagonal of a signal (its own extent, not the surface's: the pyramid of
/// a noise signal is quantised relative to the noise).
pub(crate) fn signal_diagonal(signal: &[DVec3]) -> f64 {
    crate::mesh::geometry::BoundingBox::of(signal.iter().copied()).map_or(0.0, |b| b.diagonal())
}

/// The closed loop's per-detail buffer, shared by the threads running a wave: first each
/// touched vertex's target as an f32 displacement from the vertex's value in the analysed
/// signal (set by the walk down), then, in place, its quantised detail (set by the walk up).
///
/// A displacement rather than the target itself: the last split that touches a vertex targets
/// exactly its analysed value (displacement zero, exact in any precision), and the other
/// targets are presmoothed values a fraction of an edge away, whose f32 rounding (1e-7 of that)
/// finer splits correct like any other prediction error. Half the memory of f64 targets, and
/// the details take their place without a second array.
pub(crate) struct Targets<'a> {
    cells: &'a [[AtomicU32; 3]],
}

impl<'a> Targets<'a> {
    /// Shares `buffer` for as long as the view lives.
    pub(crate) fn new(buffer: &'a mut [[i32; 3]]) -> Self {
        // SAFETY: `[i32; 3]` and `[AtomicU32; 3]` have the same size and alignment; the
        // exclusive borrow lasts as long as the view, so nothing else reads or writes the
        // memory meanwhile, and every access through the view is atomic.
        let cells = unsafe {
            std::slice::from_raw_parts(buffer.as_mut_ptr().cast::<[AtomicU32; 3]>(), buffer.len())
        };
        Targets { cells }
    }

    /// Sets entry `i`'s displacement.
    #[inline]
    pub(crate) fn set_displacement(&self, i: usize, d: DVec3) {
        let c = &self.cells[i];
        for (cell, x) in c.iter().zip(d.to_array()) {
            cell.store((x as f32).to_bits(), Relaxed);
        }
    }

    /// Entry `i`'s displacement.
    #[inline]
    pub(crate) fn displacement(&self, i: usize) -> DVec3 {
        let c = &self.cells[i];
        DVec3::from_array(
            c.each_ref()
                .map(|x| f64::from(f32::from_bits(x.load(Relaxed)))),
        )
    }

    /// Replaces entry `i` by its quantised detail.
    #[inline]
    pub(crate) fn set_detail(&self, i: usize, q: [i32; 3]) {
        for (cell, x) in self.cells[i].iter().zip(q) {
            cell.store(x as u32, Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_step_is_a_power_of_two_at_most_2_to_the_minus_21_of_the_diagonal() {
        for diagonal in [1e-6, 0.37, 1.0, 1.5, 228.8, 3e5] {
            let step = detail_step(diagonal);
            assert_eq!(step.log2().fract(), 0.0);
            assert!(step <= diagonal * 2f64.powi(-21) && step > diagonal * 2f64.powi(-22));
        }
        assert_eq!(detail_step(0.0), 2f64.powi(-21));
        assert_eq!(detail_step(f64::NAN), 2f64.powi(-21));
    }

    #[test]
    fn dequantising_gives_the_nearest_multiple_of_the_step() {
        let step = detail_step(10.0);
        let d = DVec3::new(0.123456789, -3.3e-7, 9.999);
        let back = dequantised(quantised(d, step), step);
        for (a, b) in back.to_array().iter().zip(d.to_array()) {
            assert!((a - b).abs() <= 0.5 * step);
            assert_eq!(quantised(DVec3::splat(*a), step)[0] as f64 * step, *a);
        }
    }

    #[test]
    fn huge_and_non_finite_components_saturate_instead_of_wrapping() {
        let q = quantised(DVec3::new(1e300, -1e300, f64::NAN), 1.0);
        assert_eq!(q, [i32::MAX, i32::MIN, 0]);
    }
}
