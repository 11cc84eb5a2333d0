//! Multiresolution editing (`docs/algorithms.md` §1c, "Filtering and editing"): change the signal of
//! a coarse level, then resynthesise. The details of all finer levels are added in frames built
//! from the edited prediction, so the fine structure follows the coarse deformation instead of
//! being smeared or left behind.

use super::gains::LevelGains;
use super::{DetailPyramid, PyramidError};
use glam::DVec3;

/// Drag the coarse vertices near `center` by `displacement`, fading smoothly to nothing at
/// `radius` (all in model units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveHandle {
    /// Where the handle grabs the surface.
    pub center: DVec3,
    /// How far the vertex at the centre moves.
    pub displacement: DVec3,
    /// Distance from the centre at which the influence reaches zero (> 0).
    pub radius: f64,
}

/// What a handle reached when applied: how many points lay inside its radius, and how far the
/// nearest one was (infinite without points). A handle that reaches nothing changes nothing,
/// which callers may want to report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandleReach {
    /// Points strictly inside the radius (the ones the handle moves).
    pub points: usize,
    /// Distance from the centre to the nearest point.
    pub nearest: f64,
}

impl MoveHandle {
    /// Moves `points` by `handles` (weights from their distances to each handle's centre;
    /// several handles add up) and says what each handle reached.
    pub fn apply(handles: &[MoveHandle], points: &mut [DVec3]) -> Vec<HandleReach> {
        let mut reach = vec![
            HandleReach {
                points: 0,
                nearest: f64::INFINITY,
            };
            handles.len()
        ];
        for p in points.iter_mut() {
            let mut moved = DVec3::ZERO;
            for (h, r) in handles.iter().zip(&mut reach) {
                let d = (*p - h.center).length();
                r.nearest = r.nearest.min(d);
                let w = falloff(d, h.radius);
                if w > 0.0 {
                    r.points += 1;
                }
                moved += w * h.displacement;
            }
            *p += moved;
        }
        reach
    }
}

/// The weight of a point at distance `d` from a handle of radius `r`: `(1 − (d/r)²)³` inside,
/// 0 outside. It is 1 at the centre, and its value, slope and curvature vanish at `r`, so the
/// edited region blends into the untouched surface without a visible crease.
#[inline]
pub(crate) fn falloff(d: f64, r: f64) -> f64 {
    if r.is_nan() || d.is_nan() || r <= 0.0 || d >= r {
        return 0.0;
    }
    let t = 1.0 - (d / r) * (d / r);
    t * t * t
}

impl DetailPyramid {
    /// Moves the vertices of level `level` with `handles` (weights from their distances to each
    /// handle's centre in the level's own signal; several handles add up), then resynthesises
    /// the finest level with `gains`. Returns the finest signal in PM order.
    pub fn edit(
        &self,
        level: usize,
        handles: &[MoveHandle],
        gains: &LevelGains,
    ) -> Result<Vec<DVec3>, PyramidError> {
        Ok(self.edit_reporting(level, handles, gains)?.0)
    }

    /// [`DetailPyramid::edit`], also saying what each handle reached on level `level` (a
    /// handle farther than its radius from every vertex changes nothing).
    pub fn edit_reporting(
        &self,
        level: usize,
        handles: &[MoveHandle],
        gains: &LevelGains,
    ) -> Result<(Vec<DVec3>, Vec<HandleReach>), PyramidError> {
        for h in handles {
            let valid = h.radius > 0.0
                && h.radius.is_finite()
                && h.center.is_finite()
                && h.displacement.is_finite();
            if !valid {
                return Err(PyramidError::Invalid(format!(
                    "a move handle needs a finite centre and displacement and a positive radius, got {h:?}"
                )));
            }
        }
        let mut reach = Vec::new();
        let finest = self.edit_with(level, gains, |coarse| {
            reach = MoveHandle::apply(handles, coarse);
        })?;
        Ok((finest, reach))
    }

    /// Synthesises level `level`, lets `edit` change its values (the slice holds PM vertices
    /// `0..level`), and resynthesises the finest level with `gains`.
    pub fn edit_with(
        &self,
        level: usize,
        gains: &LevelGains,
        edit: impl FnOnce(&mut [DVec3]),
    ) -> Result<Vec<DVec3>, PyramidError> {
        if level < self.n_base || level > self.n_finest {
            return Err(PyramidError::Invalid(format!(
                "edit level {level} is outside the pyramid's levels {}..={}",
                self.n_base, self.n_finest
            )));
        }
        let mut f = self.base_signal();
        self.synthesize_range(&mut f, self.n_base, level, gains);
        edit(&mut f[..level]);
        self.resynthesize_from(f, level, gains)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn falloff_is_one_at_the_centre_zero_outside_and_smooth_at_the_rim() {
        assert_eq!(falloff(0.0, 2.0), 1.0);
        assert_eq!(falloff(2.0, 2.0), 0.0);
        assert_eq!(falloff(5.0, 2.0), 0.0);
        assert_eq!(falloff(0.0, 0.0), 0.0);
        assert_eq!(falloff(f64::NAN, 1.0), 0.0);
        let eps = 1e-4;
        let slope = (falloff(2.0 - eps, 2.0) - falloff(2.0, 2.0)) / eps;
        assert!(slope.abs() < 1e-6, "{slope}");
        let mut last = 1.0;
        for i in 1..=20 {
            let w = falloff(i as f64 * 0.1, 2.0);
            assert!(w < last);
            last = w;
        }
    }
}
