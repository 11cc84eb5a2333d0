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
