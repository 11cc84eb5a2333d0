//! What a half-edge collapse may do to the shape of the surface, and the order in which a
//! stalled decimation gives those rules up (`docs/pm-legality.md`).
//!
//! A collapse `u → v` moves every face around `u` to `v`; the two faces on the edge die. The
//! shape rules judge the faces that remain:
//!
//! 1. **No fold.** A surviving face may not rotate its normal by more than the bound, which
//!    widens from the configured angle at fine levels to the fold bound at the coarse end
//!    ([`Legality::at_level`]): creases need the tight bound where faces are small, curved
//!    surfaces need the wide one where faces are large. A face whose normal is undefined (zero
//!    or near-zero area, as marching cubes and vrip emit by the thousand) can neither block nor
//!    excuse: before the collapse it is measured against the surface normal at `u` (the sum of
//!    the ring's area-weighted normals, to which degenerate faces add nothing) with the fold
//!    bound; and no face may lose its normal through a collapse, since it would escape the rule.
//! 2. **Slivers pay.** A collapse that leaves the worst face around `u` below the quality
//!    threshold, and worse than before, is not refused: it pays a penalty on top of its quadric
//!    error, in units of the ring's squared edge length, and waits for a pass whose cost cut
//!    covers it. So the fine levels stay well shaped (their errors are far below an edge
//!    length), while at the coarse end the collapses through thin triangles that keep the shape
//!    are taken. Removing slivers is free, so a cluster of degenerate faces (which costs
//!    nothing under the quadric) is collapsed away first.
//! 3. **Valence cap.**
//!
//! On meshes full of degenerate clusters the rules can still leave no legal collapse above the
//! topology's floor. The decimator then relaxes them one [`Relaxation`] step at a time (valence
//! cap, then slivers, then normals down to the fold bound) for a limited number of collapses,
//! and returns to the full rules as soon as any collapse went through. The topological rules
//! (link condition, boundaries, no pillows) are never relaxed: they keep the surface a manifold
//! and every collapse exactly invertible.

use glam::DVec3;

/// Bounds for the legality test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Legality {
    /// Largest valence the survivor may get.
    pub max_valence: usize,
    /// Cosine of the largest allowed rotation of a face normal (`cos 60°` by default here;
    /// `PmOptions` defaults to 45°).
    pub min_normal_cos: f64,
    /// Triangle quality `4√3·A / (l1² + l2² + l3²)` (1 for equilateral) below which a face left
    /// around the removed vertex counts as a sliver: a collapse that makes the worst face there
    /// a worse sliver pays a penalty on top of its error (module docs); 0 turns the penalty
    /// off, and with it the refusal of faces that would lose their normal.
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
    /// New slivers are free, and faces may lose their normal.
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

/// What a new sliver of quality 0 adds to a collapse's cost, as a fraction of the squared mean
/// edge length around the removed vertex: as much as moving the surface a tenth of an edge
/// length off its planes. Fine levels, where quadric errors are far below the edge length,
/// keep their triangles well shaped; at the coarse end, where the errors that keep the shape
/// reach that size, the penalty no longer outweighs them (`docs/pm-legality.md`).
const SLIVER_PRICE: f64 = 0.01;

/// Below this quality a face's normal is rounding noise (positions often come from 32-bit
/// files, about 7 digits).
const UNDEFINED_NORMAL_QUALITY: f64 = 1e-6;

/// Between these fractions of the input's faces the normal bound widens from the configured
/// angle to the fold bound, evenly in the logarithm of the face count. Above the first, faces are
/// small against the surface's features and turning one far means sliding across a crease;
/// below the second, faces span curved parts, and the collapses that spread the vertices evenly
/// must turn them further than a crease rule allows (`docs/pm-legality.md`).
const FINE_LEVELS: f64 = 0.05;
const COARSE_LEVELS: f64 = 0.01;

/// Where a level with `faces` of the input's `input_faces` lies between the fine levels (0, at
/// `FINE_LEVELS` and above) and the coarse end (1, at `COARSE_LEVELS` and below), evenly in the
/// logarithm of the face count.
pub(crate) fn coarseness(faces: usize, input_faces: usize) -> f64 {
    let left = faces as f64 / input_faces.max(1) as f64;
    if left >= FINE_LEVELS {
        0.0
    } else if left <= COARSE_LEVELS {
        1.0
    } else {
        (FINE_LEVELS / left).ln() / (FINE_LEVELS / COARSE_LEVELS).ln()
    }
}

impl Legality {
    /// The rules for a pass that starts with `faces` of the input's `input_faces` left: the
    /// normal bound widens towards the coarse end (see `FINE_LEVELS`).
    pub(crate) fn at_level(&self, faces: usize, input_faces: usize) -> Legality {
        let t = coarseness(faces, input_faces);
        let mut l = *self;
        if FOLD_COS < l.min_normal_cos {
            l.min_normal_cos += t * (FOLD_COS - l.min_normal_cos);
        }
        l
    }

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
    /// A face would lose its normal (become degenerate).
    Degenerate,
    /// A texture seam or material border would be broken (`docs/seams.md`).
    Seam,
    /// Legal, but at the seam floor it would cost more than four times the dearest collapse
    /// made under a pass's cost cut (`docs/seams.md`).
    Costly,
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
            Refusal::Degenerate => "face would degenerate",
            Refusal::Seam => "seam would break",
            Refusal::Costly => "dearer than the seam floor allows",
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

/// The shape rules (module docs) for moving `u` from `pu` to `pv`, given every face around `u`:
/// the refusal, or the sliver penalty the collapse pays on top of its quadric error (a squared
/// distance; 0 when it leaves no new sliver).
pub(crate) fn shape_check(
    pu: DVec3,
    pv: DVec3,
    ring: &[RingFace],
    legality: &Legality,
) -> Result<f64, Refusal> {
    let mut surface_normal = DVec3::ZERO;
    let mut ring_scale = 0.0;
    let mut worst_before = f64::INFINITY;
    for f in ring {
        let n = (f.a - pu).cross(f.b - pu);
        surface_normal += n;
        ring_scale += (f.a - pu).length_squared()
            + (f.b - f.a).length_squared()
            + (pu - f.b).length_squared();
        worst_before = worst_before.min(quality(n, pu, f.a, f.b));
    }
    // The ring as one face: its normal is defined when the ring is not degenerate as a whole.
    let surface_defined =
        2.0 * 3f64.sqrt() * surface_normal.length() > UNDEFINED_NORMAL_QUALITY * ring_scale;
    let fold_cos = legality.min_normal_cos.min(FOLD_COS);
    let mut worst_after = f64::INFINITY;
    for f in ring.iter().filter(|f| !f.dies) {
        let n_old = (f.a - pu).cross(f.b - pu);
        let n_new = (f.a - pv).cross(f.b - pv);
        let q_new = quality(n_new, pv, f.a, f.b);
        worst_after = worst_after.min(q_new);
        if q_new < UNDEFINED_NORMAL_QUALITY {
            continue; // no normal after the collapse: judged below
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
    let min_q = legality.min_quality;
    if min_q <= 0.0 || worst_after >= min_q || worst_after >= worst_before {
        return Ok(0.0);
    }
    // A face without a normal escapes the fold rule above, so none may be made where the ring
    // had none; removing a cluster of them (worst before already that low) stays allowed.
    if worst_after < UNDEFINED_NORMAL_QUALITY {
        return Err(Refusal::Degenerate);
    }
    let mean_edge_sq = ring_scale / (3 * ring.len()) as f64;
    Ok(SLIVER_PRICE * mean_edge_sq * (min_q - worst_after) / min_q)
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
            Ok(0.0)
        );
        // Onto a ring vertex: the faces on the edge die, the others stay well shaped.
        assert_eq!(
            shape_check(DVec3::ZERO, pv, &r, &Legality::default()),
            Ok(0.0)
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
            Ok(0.0)
        );
        // Through it: its new normal points down, against the surface's.
        assert_eq!(
            shape_check(DVec3::ZERO, DVec3::new(0.0, 0.6, 0.0), &r, &off),
            Err(Refusal::Normal)
        );
    }

    #[test]
    fn removing_a_sliver_is_free_and_a_new_one_pays_by_its_thinness_and_the_edge_length() {
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
        assert_eq!(shape_check(pu, pv, &r, &l), Ok(0.0));
        // Moving u of a regular ring next to an edge of it turns a good face into a sliver: the
        // collapse is legal but pays; thinner pays more, and the price scales with the ring's
        // squared edge length like the quadric error it is added to.
        let r = ring(&hexagon(0.0), &[]);
        let price = |y: f64, scale: f64, l: &Legality| {
            let r: Vec<RingFace> = r
                .iter()
                .map(|f| RingFace {
                    a: f.a * scale,
                    b: f.b * scale,
                    dies: f.dies,
                })
                .collect();
            shape_check(pu, DVec3::new(0.0, y, 0.0) * scale, &r, l).unwrap()
        };
        let near = price(0.85, 1.0, &l);
        assert!(near > 0.0);
        assert!(price(0.86, 1.0, &l) > near);
        assert!((price(0.85, 10.0, &l) / near - 100.0).abs() < 1e-9);
        // Not past a tenth of an edge length squared: a sliver never outweighs a real error.
        assert!(near < 0.01);
        // The relaxed rules and `min_quality` 0 do not charge it.
        assert_eq!(price(0.85, 1.0, &l.relaxed(Relaxation::Slivers)), 0.0);
        let off = Legality {
            min_quality: 0.0,
            ..l
        };
        assert_eq!(price(0.85, 1.0, &off), 0.0);
    }

    #[test]
    fn a_face_without_a_normal_is_never_made_where_the_ring_had_none() {
        // u moved onto the edge between two ring vertices flattens the face between them: it
        // would escape the fold rule, so the collapse is refused (until slivers are relaxed).
        let r = ring(&hexagon(0.0), &[]);
        let around = hexagon(0.0);
        let on_edge = 0.5 * (around[1] + around[2]);
        let l = Legality::default();
        assert_eq!(
            shape_check(DVec3::ZERO, on_edge, &r, &l),
            Err(Refusal::Degenerate)
        );
        assert_eq!(
            shape_check(DVec3::ZERO, on_edge, &r, &l.relaxed(Relaxation::Slivers)),
            Ok(0.0)
        );
    }

    #[test]
    fn coarseness_runs_from_the_fine_levels_to_the_coarse_end_in_log_faces() {
        assert_eq!(coarseness(1000, 1000), 0.0);
        assert_eq!(coarseness(50, 1000), 0.0);
        assert_eq!(coarseness(10, 1000), 1.0);
        assert_eq!(coarseness(0, 1000), 1.0);
        // The geometric middle of 5 % and 1 % is half way.
        let middle = coarseness(22_360_680, 1_000_000_000);
        assert!((middle - 0.5).abs() < 1e-6, "{middle}");
        assert_eq!(coarseness(0, 0), 1.0);
    }

    #[test]
    fn the_normal_bound_widens_to_the_fold_bound_towards_the_coarse_end() {
        let l = Legality {
            min_normal_cos: 45f64.to_radians().cos(),
            ..Legality::default()
        };
        assert_eq!(l.at_level(1000, 1000), l);
        assert_eq!(l.at_level(50, 1000), l);
        assert_eq!(l.at_level(10, 1000).min_normal_cos, FOLD_COS);
        assert_eq!(l.at_level(1, 1000).min_normal_cos, FOLD_COS);
        let middle = l.at_level(22, 1000).min_normal_cos;
        assert!(middle < l.min_normal_cos && middle > FOLD_COS);
        // A bound already wider than the fold bound stays as it is.
        let wide = Legality {
            min_normal_cos: -0.5,
            ..l
        };
        assert_eq!(wide.at_level(1, 1000), wide);
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
