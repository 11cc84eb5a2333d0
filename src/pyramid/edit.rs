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

/// One move of a sequence of edits ([`DetailPyramid::edit_levels`]): `handle` applied to the
/// signal of level `level`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelMove {
    /// The level (vertex count) whose vertices move.
    pub level: usize,
    /// Where and how far.
    pub handle: MoveHandle,
}

fn check_handle(h: &MoveHandle) -> Result<(), PyramidError> {
    let valid = h.radius > 0.0
        && h.radius.is_finite()
        && h.center.is_finite()
        && h.displacement.is_finite();
    if !valid {
        return Err(PyramidError::Invalid(format!(
            "a move handle needs a finite centre and displacement and a positive radius, got {h:?}"
        )));
    }
    Ok(())
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
        handles.iter().try_for_each(check_handle)?;
        let mut reach = Vec::new();
        let finest = self.edit_with(level, gains, |coarse| {
            reach = MoveHandle::apply(handles, coarse);
        })?;
        Ok((finest, reach))
    }

    /// A sequence of edits at several levels: synthesis runs coarse to fine and applies each
    /// move when it reaches the move's level (moves of one level in the order given, each
    /// seeing the ones before), then goes on to the finest level with `gains`. A single move
    /// gives exactly [`DetailPyramid::edit`] with its level and handle.
    pub fn edit_levels(
        &self,
        moves: &[LevelMove],
        gains: &LevelGains,
    ) -> Result<Vec<DVec3>, PyramidError> {
        for m in moves {
            self.check_edit_level(m.level)?;
            check_handle(&m.handle)?;
        }
        let mut order: Vec<&LevelMove> = moves.iter().collect();
        order.sort_by_key(|m| m.level);
        let mut f = self.base_signal();
        let mut reached = self.n_base;
        for m in order {
            self.synthesize_range(&mut f, reached, m.level, gains);
            reached = m.level;
            MoveHandle::apply(std::slice::from_ref(&m.handle), &mut f[..m.level]);
        }
        self.resynthesize_from(f, reached, gains)
    }

    fn check_edit_level(&self, level: usize) -> Result<(), PyramidError> {
        if level < self.n_base || level > self.n_finest {
            return Err(PyramidError::Invalid(format!(
                "edit level {level} is outside the pyramid's levels {}..={}",
                self.n_base, self.n_finest
            )));
        }
        Ok(())
    }

    /// Synthesises level `level`, lets `edit` change its values (the slice holds PM vertices
    /// `0..level`), and resynthesises the finest level with `gains`.
    pub fn edit_with(
        &self,
        level: usize,
        gains: &LevelGains,
        edit: impl FnOnce(&mut [DVec3]),
    ) -> Result<Vec<DVec3>, PyramidError> {
        self.check_edit_level(level)?;
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

    fn small_pyramid() -> DetailPyramid {
        use crate::pm::{PmOptions, ProgressiveMesh};
        let (p, t) = crate::mesh::shapes::torus(30, 20, |u, v| {
            let r = 2.0 + (1.0 + 0.1 * (6.0 * u).sin()) * v.cos();
            DVec3::new(r * u.cos(), r * u.sin(), v.sin())
        });
        let mesh = crate::mesh::Mesh::from_triangles(&p, &t).unwrap().mesh;
        let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &crate::NoProgress).unwrap();
        let relax = crate::relax::SecondDifference::default();
        DetailPyramid::analyze(&pm, &relax, &crate::NoProgress).unwrap()
    }

    #[test]
    fn one_level_move_is_the_single_edit_and_moves_apply_coarse_to_fine() {
        let p = small_pyramid();
        let (n0, n) = (p.n_base_vertices(), p.n_vertices());
        let gains = crate::Filter::new().gain(n0, n, 1.5).resolve(1.0);
        let handle = MoveHandle {
            center: DVec3::new(3.0, 0.0, 0.0),
            displacement: DVec3::Z * 0.4,
            radius: 1.5,
        };
        let coarse = LevelMove {
            level: n0 + (n - n0) / 4,
            handle,
        };
        let single = p.edit(coarse.level, &[handle], &gains).unwrap();
        assert_eq!(p.edit_levels(&[coarse], &gains).unwrap(), single);
        assert_ne!(single, p.synthesize(&gains));
        let fine = LevelMove {
            level: n0 + (n - n0) / 2,
            handle: MoveHandle {
                center: DVec3::new(-3.0, 0.0, 0.0),
                ..handle
            },
        };
        let both = p.edit_levels(&[fine, coarse], &gains).unwrap();
        assert_eq!(p.edit_levels(&[coarse, fine], &gains).unwrap(), both);
        assert_ne!(both, single);
        assert_eq!(p.edit_levels(&[], &gains).unwrap(), p.synthesize(&gains));
        let outside = LevelMove {
            level: n + 1,
            handle,
        };
        assert!(p.edit_levels(&[coarse, outside], &gains).is_err());
    }
}
