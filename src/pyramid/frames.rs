//! Local frames for details (`docs/algorithms.md` §1c, "Local frames").
//!
//! A detail is stored as `d = F (f − q)`, with `F` the orthonormal frame `(t1, t2, n)` of the
//! vertex in the *predicted* geometry `G` of its level (predictions on the split's vertices, the
//! coarser signal elsewhere, the level's connectivity). Synthesis knows `G` before it knows the
//! detail, so it rebuilds the same frame and adds `Fᵀ d`. When the coarse surface bends or
//! moves, the frames follow it, and so do the details.
//!
//! * `n`: area-weighted normal of the vertex's fan in `G`;
//! * `t1`: the direction to a reference neighbour (the survivor for the new vertex, the new
//!   vertex for its ring), projected into the tangent plane; when that projection is tiny, the
//!   next fan neighbour counter-clockwise is used, and as a last resort the world axis most
//!   perpendicular to `n`;
//! * `t2 = n × t1`.
//!
//! A fan whose normal vanishes (all triangles degenerate in `G`) gets the world frame.
//!
//! Any fixed rule reconstructs perfectly *if synthesis sees the very `G` the analysis saw*, but
//! it sees it only up to rounding (about 1e-15 of the bounding-box diagonal per level). A frame
//! is a discontinuous function of `G` where a fan or a reference direction has collapsed: the
//! normal of a fan shrunk to a point is the direction of its rounding noise, and the two passes
//! would pick unrelated frames, turning a detail of length 1 into an error of length 1. So
//! "degenerate" is decided against an absolute length, [`FRAME_LENGTH_FLOOR`] times the
//! diagonal, far above rounding (and far enough that frames just above it are still
//! well-conditioned): a normal shorter than the floor times the fan's perimeter
//! bound, or a projected reference direction shorter than the floor, does not count.

use glam::DVec3;

/// An orthonormal frame as rows `(t1, t2, n)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame {
    /// First tangent.
    pub t1: DVec3,
    /// Second tangent, `n × t1`.
    pub t2: DVec3,
    /// Unit normal.
    pub n: DVec3,
}

impl Frame {
    /// The world frame `(x, y, z)`.
    pub(crate) const WORLD: Frame = Frame {
        t1: DVec3::X,
        t2: DVec3::Y,
        n: DVec3::Z,
    };

    /// Coordinates of the world vector `x` in this frame.
    #[inline]
    pub(crate) fn to_local(self, x: DVec3) -> DVec3 {
        DVec3::new(self.t1.dot(x), self.t2.dot(x), self.n.dot(x))
    }

    /// The world vector with frame coordinates `d`, tangential part scaled by `tangent_gain`
    /// and normal part by `normal_gain`.
    #[inline]
    pub(crate) fn to_world_scaled(self, d: DVec3, tangent_gain: f64, normal_gain: f64) -> DVec3 {
        tangent_gain * (self.t1 * d.x + self.t2 * d.y) + normal_gain * (self.n * d.z)
    }
}

/// Relative size below which a projected reference direction counts as degenerate.
const DEGENERATE_TANGENT: f64 = 1e-12;

/// Lengths below this fraction of the bounding-box diagonal count as zero when building frames
/// (see the module docs). Near the floor a frame is continuous but ill-conditioned: rounding
/// of relative size δ ≈ 1e-15 in `G` turns it by about δ / floor, which moves a detail `d` by
/// `|d| · δ / floor`; at 1e-6 that is below 1e-9 of `|d|`. (At 1e-9 the fuzzer found a sliver
/// fan whose vertex came back 3.6e-6 off.) Fans with spokes shorter than a millionth of the
/// model, or that flat, get the world frame instead.
pub(crate) const FRAME_LENGTH_FLOOR: f64 = 1e-6;

/// The `min_length` of [`vertex_frame`] for a surface with bounding-box diagonal
/// `bbox_diagonal`; analysis and synthesis both take it from here, so they build the same
/// frames.
#[inline]
pub(crate) fn frame_min_length(bbox_diagonal: f64) -> f64 {
    FRAME_LENGTH_FLOOR * bbox_diagonal
}

/// An integer index into a signal array: the pyramid stores local indices in the narrowest of
/// `u8`, `u16`, `u32` that fits.
pub(crate) trait LocalIndex: Copy + Send + Sync {
    /// The index as `usize`.
    fn at(self) -> usize;
}

impl LocalIndex for u8 {
    #[inline(always)]
    fn at(self) -> usize {
        self as usize
    }
}

impl LocalIndex for u16 {
    #[inline(always)]
    fn at(self) -> usize {
        self as usize
    }
}

impl LocalIndex for u32 {
    #[inline(always)]
    fn at(self) -> usize {
        self as usize
    }
}

/// The frame of vertex `j` from the signal `g` (indexed by vertex), its counter-clockwise fan
/// of neighbours (`open`: `j` is a boundary vertex) and the preferred reference neighbour;
/// `min_length` ([`frame_min_length`] of the diagonal) is the length below which directions
/// are not trusted.
///
/// The fan's triangles are `(j, fan[k], fan[k+1 mod m])` for every `k`, except `k = 0` when the
/// fan is open: a boundary vertex's circulation starts at its boundary edge, which has no face.
#[inline]
pub(crate) fn vertex_frame<I: LocalIndex>(
    g: &[DVec3],
    j: usize,
    fan: &[I],
    open: bool,
    reference: usize,
    min_length: f64,
) -> Frame {
    let pj = g[j];
    let m = fan.len();
    let mut normal = DVec3::ZERO;
    let mut longest2 = 0.0f64;
    if m >= 2 {
        // Triangles (fan[k], fan[k+1]) for k = 0..m-2, then the closing (fan[m-1], fan[0]);
        // an open fan's gap is the first pair. Each neighbour is loaded once, no modulo.
        let first = g[fan[0].at()] - pj;
        longest2 = first.length_squared();
        let mut prev = first;
        for (k, &x) in fan[1..].iter().enumerate() {
            let cur = g[x.at()] - pj;
            longest2 = longest2.max(cur.length_squared());
            // Pair (fan[k], fan[k+1]); skipped for k = 0 when open.
            if k > 0 || !open {
                normal += prev.cross(cur);
            }
            prev = cur;
        }
        normal += prev.cross(first);
    }
    // Rounding noise of size ε in the positions moves the normal by at most about
    // 2·m·ε·(longest spoke); a normal within the floor's share of that bound is noise.
    let noise = m as f64 * min_length;
    if normal.length_squared() <= noise * noise * longest2 {
        return Frame::WORLD;
    }
    let n = normal.normalize_or_zero();
    if n == DVec3::ZERO || !n.is_finite() {
        return Frame::WORLD;
    }
    // Compared squared: one square root per frame instead of three.
    let tangent_of = |r: DVec3| {
        let t = r - r.dot(n) * n;
        let len2 = t.length_squared();
        let usable = len2 > (DEGENERATE_TANGENT * DEGENERATE_TANGENT) * r.length_squared()
            && len2 > min_length * min_length
            && len2 > 0.0
            && len2.is_finite();
        usable.then(|| t / len2.sqrt())
    };
    let t1 = tangent_of(g[reference] - pj)
        .or_else(|| {
            let start = fan
                .iter()
                .position(|&x| x.at() == reference)
                .map_or(0, |p| p + 1);
            (0..m).find_map(|i| tangent_of(g[fan[(start + i) % m].at()] - pj))
        })
        .unwrap_or_else(|| {
            // The world axis most perpendicular to n always has a usable projection.
            let axis = if n.x.abs() <= n.y.abs() && n.x.abs() <= n.z.abs() {
                DVec3::X
            } else if n.y.abs() <= n.z.abs() {
                DVec3::Y
            } else {
                DVec3::Z
            };
            (axis - axis.dot(n) * n).normalize()
        });
    Frame {
        t1,
        t2: n.cross(t1),
        n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_orthonormal(f: &Frame) -> bool {
        let ok = |a: f64, b: f64| (a - b).abs() < 1e-12;
        ok(f.t1.length(), 1.0)
            && ok(f.t2.length(), 1.0)
            && ok(f.n.length(), 1.0)
            && ok(f.t1.dot(f.t2), 0.0)
            && ok(f.t1.dot(f.n), 0.0)
            && ok(f.t2.dot(f.n), 0.0)
            && ok(f.t1.cross(f.t2).dot(f.n), 1.0)
    }

    #[test]
    fn planar_fan_gives_the_plane_normal_and_points_at_the_reference() {
        // Hexagon around vertex 0 in the xy plane, CCW seen from +z.
        let mut g = vec![DVec3::ZERO];
        for k in 0..6 {
            let a = k as f64 * std::f64::consts::FRAC_PI_3;
            g.push(DVec3::new(a.cos(), a.sin(), 0.0));
        }
        let fan: Vec<u32> = (1..=6).collect();
        let f = vertex_frame(&g, 0, &fan, false, 2, 0.0);
        assert!(is_orthonormal(&f));
        assert!((f.n - DVec3::Z).length() < 1e-12);
        assert!((f.t1 - g[2]).length() < 1e-12);
        let x = DVec3::new(0.3, -1.2, 0.7);
        let back = f.to_world_scaled(f.to_local(x), 1.0, 1.0);
        assert!((back - x).length() < 1e-15);
        // Normal-only gain leaves the tangential part alone.
        let s = f.to_world_scaled(f.to_local(x), 1.0, 0.0);
        assert!((s - DVec3::new(0.3, -1.2, 0.0)).length() < 1e-15);
    }

    #[test]
    fn open_fan_skips_the_boundary_gap() {
        // Half-disc: neighbours from angle 0 to π, the gap closing the far side.
        let mut g = vec![DVec3::ZERO];
        for k in 0..4 {
            let a = k as f64 * std::f64::consts::PI / 3.0;
            g.push(DVec3::new(a.cos(), a.sin(), 0.0));
        }
        // The circulation of a boundary vertex starts at its boundary edge: here the edge to the
        // neighbour at angle π, followed by angle 0, π/3, 2π/3 … so the gap is (fan[0], fan[1]).
        let fan = [4u32, 1, 2, 3];
        let f = vertex_frame(&g, 0, &fan, true, 1, 0.0);
        assert!((f.n - DVec3::Z).length() < 1e-12, "{:?}", f.n);
        // Treating it as closed would add the reflex triangle (0, 4, 1) with zero area here; tilt
        // it to see the difference.
        g[4].z = 1.0;
        let open = vertex_frame(&g, 0, &fan, true, 1, 0.0);
        let closed = vertex_frame(&g, 0, &fan, false, 1, 0.0);
        // The bogus triangle (0, 4, 1) would add (−1, 0, 1) × (1, 0, 0) = +y to the normal.
        assert!(closed.n.y - open.n.y > 0.1, "{:?} {:?}", closed.n, open.n);
        assert!(is_orthonormal(&open) && is_orthonormal(&closed));
    }

    #[test]
    fn degenerate_reference_falls_back_to_the_next_neighbour_and_to_the_world() {
        let g = vec![
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(0.0, 0.0, 2.0), // straight above: no tangential part
        ];
        let f = vertex_frame(&g, 0, &[1u32, 2, 3], false, 4, 0.0);
        assert!(is_orthonormal(&f));
        assert!((f.t1 - DVec3::X).length() < 1e-12);
        // All neighbours coincide with the vertex: no normal → world frame.
        let z = vec![DVec3::ZERO; 4];
        assert_eq!(
            vertex_frame(&z, 0, &[1u32, 2, 3], false, 1, 0.0),
            Frame::WORLD
        );
        let nan = vec![DVec3::splat(f64::NAN); 4];
        assert_eq!(
            vertex_frame(&nan, 0, &[1u32, 2, 3], false, 1, 0.0),
            Frame::WORLD
        );
    }

    #[test]
    fn fans_collapsed_to_rounding_noise_get_the_world_frame_in_both_passes() {
        // An isolated triangle whose corners were snapped together: the analysis sees the
        // corners equal, synthesis sees them 1e-16 apart. Without a floor the second frame
        // points along the noise and a detail of length 1 comes back rotated.
        let exact = vec![DVec3::new(2.0, 0.0, 0.06); 3];
        let mut noisy = exact.clone();
        noisy[1].y += 3e-16;
        noisy[2].z -= 2e-16;
        let min_length = frame_min_length(10.0);
        for g in [&exact, &noisy] {
            assert_eq!(
                vertex_frame(g, 0, &[1u32, 2], true, 1, min_length),
                Frame::WORLD
            );
        }
        // Without the floor the noisy fan has a "normal".
        assert_ne!(
            vertex_frame(&noisy, 0, &[1u32, 2], true, 1, 0.0),
            Frame::WORLD
        );
        // A sound fan whose reference neighbour sits within rounding of the vertex: the
        // tangent comes from the next neighbour in both passes.
        let mut g = vec![
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::ZERO,
        ];
        let a = vertex_frame(&g, 0, &[1u32, 2, 3], false, 4, min_length);
        g[4] = DVec3::new(1e-16, -2e-16, 0.0);
        let b = vertex_frame(&g, 0, &[1u32, 2, 3], false, 4, min_length);
        assert_eq!(a, b);
        assert!((a.t1 - DVec3::X).length() < 1e-12);
    }
}
