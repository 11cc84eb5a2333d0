//! What a half-edge collapse may do to the shape of the surface, and the order in which a
//! stalled decimation gives those rules up (`docs/pm-legality.md`).
//!
//! A collapse `u → v` moves every face around `u` to `v`; the two faces on the edge die. The
//! shape rules judge the faces that remain:
//!
//! 1. **No fold.** A surviving face may not rotate its normal by more than the bound. A face
//!    whose normal is undefined (zero or near-zero area, as marching cubes and vrip emit by the
//!    thousand) can neither block nor excuse: before the collapse it is measured against the
//!    surface normal at `u` (the sum of the ring's area-weighted normals, to which degenerate
//!    faces add nothing) with the fold bound; after it, a face without a normal is left to the
//!    sliver rule.
//! 2. **No new slivers.** The worst face quality around `u` may not fall below the threshold
//!    unless it was already that bad, and the number of slivers there may not grow. So a
//!    collapse that removes a sliver may leave a milder one behind, and a cluster of degenerate
//!    faces (which costs nothing under the quadric) can be collapsed away, while a collapse that
//!    makes a sliver out of a good face waits for another collapse to do its job.
//! 3. **Valence cap.**
//!
//! These rules protect the hierarchy's shape, but on meshes full of degenerate clusters they
//! can leave no legal collapse far above the topology's floor. The decimator then relaxes them
//! one [`Relaxation`] step at a time (valence cap, then slivers, then normals down to the fold
//! bound) for a limited number of collapses, and returns to the full rules as soon as any
//! collapse went through. The topological rules (link condition, boundaries, no pillows) are
//! never relaxed: they keep the surface a manifold and every collapse exactly invertible.

use glam::DVec3;

/// Bounds for the legality test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Legality {
    /// Largest valence the survivor may get.
    pub max_valence: usize,
    /// Cosine of the largest allowed rotation of a face normal (`cos 60°` by default here;
    /// `PmOptions` defaults to 45°).
    pub min_normal_cos: f64,
    /// Smallest triangle quality `4√3·A / (l1² + l2² + l3²)` (1 for equilateral) the faces
    /// around the removed vertex may be left with, unless they were already worse (see the
    /// module docs for the exact rule); 0 turns the rule off.
    pub min_quality: f64,
}

impl Default for Legality {
    fn default() -> Self {
        Legality {
            max_valence: 32,
            min_normal_cos: 0.5,
            min_quality: 0.05,
        }
    }
}

/// How far a decimation that found no legal collapse has relaxed the shape rules; each step
/// keeps the ones before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Relaxation {
    /// Every rule as configured.
    None,
    /// The valence cap is lifted.
    Valence,
    /// New slivers are allowed.
    Slivers,
    /// Normals may rotate up to the fold bound (about 75°) instead of the configured angle.
    Normals,
}

impl Relaxation {
    /// The next step, `None` after the last.
    pub fn next(self) -> Option<Relaxation> {
        match self {
            Relaxation::None => Some(Relaxation::Valence),
            Relaxation::Valence => Some(Relaxation::Slivers),
            Relaxation::Slivers => Some(Relaxation::Normals),
            Relaxation::Normals => None,
        }
    }
}

/// Cosine of the fold bound: the largest normal rotation ever allowed, and the bound for faces
/// whose own normal was undefined. Not 0 (a right angle): a series of collapses just under 90°
/// each could still turn a face over.
pub(crate) const FOLD_COS: f64 = 0.25;

/// Below this quality a face's normal is rounding noise (positions often come from 32-bit
/// files, about 7 digits).
const UNDEFINED_NORMAL_QUALITY: f64 = 1e-6;

impl Legality {
    /// The rules with the relaxation steps up to `step` applied.
    pub(crate) fn relaxed(&self, step: Relaxation) -> Legality {
        let mut l = *self;
        if step >= Relaxation::Valence {
            l.max_valence = usize::MAX;
        }
        if step >= Relaxation::Slivers {
            l.min_quality = 0.0;
        }
        if step >= Relaxation::Normals {
            l.min_normal_cos = l.min_normal_cos.min(FOLD_COS);
        }
        l
    }
}

/// The rule that refused a collapse.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Refusal {
    /// An interior edge from a boundary vertex: the boundary would be pinched.
    Boundary,
    /// A face with both outer edges on the boundary would be left dangling.
    DanglingFace,
    /// A wing vertex of valence 3 would be left on a degenerate pillow (the tetrahedron rule).
    Pillow,
    /// The link condition: the surface would stop being a manifold.
    Link,
    /// The survivor would exceed the valence cap.
    Valence,
    /// A face would turn by more than the normal bound.
    Normal,
    /// A new sliver.
    Sliver,
}

impl Refusal {
    /// A few words for reports.
    pub(crate) fn describe(self) -> &'static str {
        match self {
            Refusal::Boundary => "boundary would pinch",
            Refusal::DanglingFace => "face would dangle",
            Refusal::Pillow => "valence-3 wing",
            Refusal::Link => "link condition",
            Refusal::Valence => "valence cap",
            Refusal::Normal => "normal would fold",
            Refusal::Sliver => "new sliver",
        }
    }
}

/// A face around the removed vertex `u`: its other two corners in the face's order after `u`,
/// and whether the collapse deletes it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RingFace {
    pub a: DVec3,
    pub b: DVec3,
    pub dies: bool,
}

/// Triangle quality `4√3·A / Σ l²` from its doubled-area normal.
#[inline]
pub(crate) fn quality(n: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let s = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
    if s > 0.0 {
        2.0 * 3f64.sqrt() * n.length() / s
    } else {
        0.0
    }
}

/// The shape rules (module docs) for moving `u` from `pu` to `pv`, given every face around `u`.
pub(crate) fn shape_check(
    pu: DVec3,
    pv: DVec3,
    ring: &[RingFace],
    legality: &Legality,
) -> Result<(), Refusal> {
    let min_q = legality.min_quality;
    let mut surface_normal = DVec3::ZERO;
    let mut ring_scale = 0.0;
    let mut worst_before = f64::INFINITY;
    let mut slivers_before = 0;
    for f in ring {
        let n = (f.a - pu).cross(f.b - pu);
        surface_normal += n;
        ring_scale += (f.a - pu).length_squared()
            + (f.b - f.a).length_squared()
            + (pu - f.b).length_squared();
        let q = quality(n, pu, f.a, f.b);
        worst_before = worst_before.min(q);
        slivers_before += (q < min_q) as usize;
    }
    // The ring as one face: its normal is defined when the ring is not degenerate as a whole.
    let surface_defined =
        2.0 * 3f64.sqrt() * surface_normal.length() > UNDEFINED_NORMAL_QUALITY * ring_scale;
    let fold_cos = legality.min_normal_cos.min(FOLD_COS);
    let mut worst_after = f64::INFINITY;
    let mut slivers_after = 0;
    for f in ring.iter().filter(|f| !f.dies) {
        let n_old = (f.a - pu).cross(f.b - pu);
        let n_new = (f.a - pv).cross(f.b - pv);
        let q_new = quality(n_new, pv, f.a, f.b);
        worst_after = worst_after.min(q_new);
        slivers_after += (q_new < min_q) as usize;
        if q_new < UNDEFINED_NORMAL_QUALITY {
            continue; // no normal after the collapse: the sliver rule judges it
        }
        let (reference, cos) = if quality(n_old, pu, f.a, f.b) >= UNDEFINED_NORMAL_QUALITY {
            (n_old, legality.min_normal_cos)
        } else if surface_defined {
            (surface_normal, fold_cos)
        } else {
            continue;
        };
        if reference.dot(n_new) <= cos * reference.length() * n_new.length() {
            return Err(Refusal::Normal);
        }
    }
    if worst_after < min_q && (worst_after < worst_before || slivers_after > slivers_before) {
        return Err(Refusal::Sliver);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fan of faces `(u, around[i], around[i + 1])`.
    fn ring(around: &[DVec3], dying: &[usize]) -> Vec<RingFace> {
        (0..around.len())
            .map(|i| RingFace {
                a: around[i],
                b: around[(i + 1) % around.len()],
                dies: dying.contains(&i),
            })
            .collect()
    }

    fn hexagon(z: f64) -> Vec<DVec3> {
        (0..6)
            .map(|i| {
                let t = i as f64 * std::f64::consts::TAU / 6.0;
                DVec3::new(t.cos(), t.sin(), z)
            })
            .collect()
    }

    #[test]
    fn a_small_move_inside_a_flat_ring_is_legal() {
        let around = hexagon(0.0);
        let r = ring(&around, &[0, 5]);
        let pv = around[0];
        assert_eq!(
            shape_check(DVec3::ZERO, pv * 0.1, &r, &Legality::default()),
            Ok(())
        );
        // Onto a ring vertex: the faces on the edge die, the others stay well shaped.
        assert_eq!(
            shape_check(DVec3::ZERO, pv, &r, &Legality::default()),
            Ok(())
        );
    }

    #[test]
    fn moving_past_the_ring_folds_faces_over() {
        let around = hexagon(0.0);
        let r = ring(&around, &[]);
        let outside = DVec3::new(3.0, 0.0, 0.0);
        let relaxed = Legality::default().relaxed(Relaxation::Normals);
        assert_eq!(
            shape_check(DVec3::ZERO, outside, &r, &relaxed),
            Err(Refusal::Normal)
        );
    }

    #[test]
    fn a_degenerate_face_is_judged_against_the_surface_normal() {
        // u sits on the segment between two ring vertices: the face between them has no
        // normal. Moving u below the plane turns that face over relative to the surface.
        let mut around = hexagon(0.0);
        around[1] = DVec3::new(0.5, 0.0, 0.0);
        around[2] = DVec3::new(-0.5, 0.0, 0.0);
        let r = ring(&around, &[]);
        let off = Legality {
            min_quality: 0.0,
            ..Legality::default()
        };
        // Up and away from the degenerate face along the surface: fine.
        assert_eq!(
            shape_check(DVec3::ZERO, DVec3::new(0.0, -0.1, 0.0), &r, &off),
            Ok(())
        );
        // Through it: its new normal points down, against the surface's.
        assert_eq!(
            shape_check(DVec3::ZERO, DVec3::new(0.0, 0.6, 0.0), &r, &off),
            Err(Refusal::Normal)
        );
    }

    #[test]
    fn removing_a_sliver_may_leave_a_milder_one_but_not_a_new_one() {
        let l = Legality::default();
        let pu = DVec3::ZERO;
        // A needle: u and v almost coincide; the two faces on the edge are slivers and die.
        let pv = DVec3::new(1e-3, 0.0, 0.0);
        let around = [
            pv,
            DVec3::new(0.5, 1.0, 0.0),
            DVec3::new(-0.5, 1.0, 0.0),
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(-0.5, -1.0, 0.0),
            DVec3::new(0.5, -1.0, 0.0),
        ];
        let r = ring(&around, &[0, 5]);
        assert_eq!(shape_check(pu, pv, &r, &l), Ok(()));
        // Moving u of a regular ring next to an edge of it turns a good face into a sliver:
        // refused while other collapses may do the job, allowed once slivers are relaxed.
        let near_edge = DVec3::new(0.0, 0.85, 0.0);
        let r = ring(&hexagon(0.0), &[]);
        assert_eq!(shape_check(pu, near_edge, &r, &l), Err(Refusal::Sliver));
        let relaxed = l.relaxed(Relaxation::Slivers);
        assert_eq!(shape_check(pu, near_edge, &r, &relaxed), Ok(()));
    }

    #[test]
    fn relaxation_steps_keep_the_ones_before() {
        let l = Legality {
            max_valence: 12,
            min_normal_cos: 0.7,
            min_quality: 0.1,
        };
        assert_eq!(l.relaxed(Relaxation::None), l);
        let v = l.relaxed(Relaxation::Valence);
        assert_eq!((v.max_valence, v.min_quality), (usize::MAX, 0.1));
        let s = l.relaxed(Relaxation::Slivers);
        assert_eq!(
            (s.max_valence, s.min_quality, s.min_normal_cos),
            (usize::MAX, 0.0, 0.7)
        );
        let n = l.relaxed(Relaxation::Normals);
        assert_eq!(n.min_normal_cos, FOLD_COS);
        assert_eq!(Relaxation::Normals.next(), None);
    }
}
