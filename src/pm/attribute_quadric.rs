//! Attribute quadrics for texture coordinates (Garland & Heckbert 1998, "Simplifying surfaces
//! with color and texture using quadric error metrics"; Hoppe 1999, "New quadric metric for
//! simplifying meshes with appearance attributes").
//!
//! Each face carries the linear texture-coordinate field that interpolates its corners,
//! `uv(p) = G p + e` with the gradient `G` (2 × 3) lying in the face's plane. A wedge (the
//! corners of one vertex that share a value) sums, area-weighted, the squared deviation
//! `|G p + e − a|²` of its faces' fields from a value `a` at a position `p`. A half-edge collapse
//! moves no vertex and invents no value: the removed vertex's wedge takes the position and the
//! value of the survivor's wedge on the same side, and the quadric, evaluated there, measures how
//! far that value is from what the faces around both wedges predicted — Hoppe's
//! "discontinuity-preserving" attribute error without solving for a new value.
//!
//! Steps: [`AttributeQuadric::of_triangle`] solves the gradient of a triangle's field (zero along
//! the normal, so the field extends off the plane unchanged), [`AttributeQuadric::add`] merges
//! wedges, [`AttributeQuadric::raw`] evaluates the area-weighted sum (texture units² × area).

use glam::{DVec2, DVec3};

/// `Σ w·|G p + e − a|²` over a wedge's faces, stored as the sums its expansion needs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct AttributeQuadric {
    /// `Σ w·(g_u g_uᵀ + g_v g_vᵀ)`, upper triangle (xx, xy, xz, yy, yz, zz).
    gg: [f64; 6],
    /// `Σ w·(g_u e_u + g_v e_v)`.
    ge: DVec3,
    /// `Σ w·(e_u² + e_v²)`.
    ee: f64,
    /// `Σ w·g_u`, `Σ w·g_v`.
    g: [DVec3; 2],
    /// `Σ w·e`.
    e: DVec2,
    /// `Σ w` (the faces' area).
    pub weight: f64,
}

impl AttributeQuadric {
    /// The quadric of the field interpolating `uv` at the corners `p` of a triangle, weighted
    /// by its area; `None` for a triangle without area or with non-finite values.
    pub(crate) fn of_triangle(p: [DVec3; 3], uv: [DVec2; 3]) -> Option<AttributeQuadric> {
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let n = e1.cross(e2);
        let nn = n.length_squared();
        if !(nn > 0.0 && nn.is_finite()) {
            return None;
        }
        // The gradient g of a linear function with values a0, a1, a2 satisfies g·e1 = a1 − a0,
        // g·e2 = a2 − a0 and g·n = 0; (e2 × n)·e1 = (n × e1)·e2 = |n|² gives it directly.
        let (b1, b2) = (e2.cross(n) / nn, n.cross(e1) / nn);
        let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
        let gu = b1 * d1.x + b2 * d2.x;
        let gv = b1 * d1.y + b2 * d2.y;
        let e = DVec2::new(uv[0].x - gu.dot(p[0]), uv[0].y - gv.dot(p[0]));
        let w = 0.5 * nn.sqrt();
        let q = AttributeQuadric {
            gg: [
                w * (gu.x * gu.x + gv.x * gv.x),
                w * (gu.x * gu.y + gv.x * gv.y),
                w * (gu.x * gu.z + gv.x * gv.z),
                w * (gu.y * gu.y + gv.y * gv.y),
                w * (gu.y * gu.z + gv.y * gv.z),
                w * (gu.z * gu.z + gv.z * gv.z),
            ],
            ge: w * (gu * e.x + gv * e.y),
            ee: w * e.length_squared(),
            g: [w * gu, w * gv],
            e: w * e,
            weight: w,
        };
        q.is_finite().then_some(q)
    }

    fn is_finite(&self) -> bool {
        self.gg.iter().all(|x| x.is_finite())
            && self.ge.is_finite()
            && self.ee.is_finite()
            && self.g[0].is_finite()
            && self.g[1].is_finite()
            && self.e.is_finite()
            && self.weight.is_finite()
    }

    /// Componentwise sum.
    pub(crate) fn add(&mut self, o: &AttributeQuadric) {
        for k in 0..6 {
            self.gg[k] += o.gg[k];
        }
        self.ge += o.ge;
        self.ee += o.ee;
        self.g[0] += o.g[0];
        self.g[1] += o.g[1];
        self.e += o.e;
        self.weight += o.weight;
    }

    /// `Σ w·|G p + e − a|²` (never negative).
    pub(crate) fn raw(&self, p: DVec3, a: DVec2) -> f64 {
        let m = &self.gg;
        let pgp = p.x * (m[0] * p.x + 2.0 * (m[1] * p.y + m[2] * p.z))
            + p.y * (m[3] * p.y + 2.0 * m[4] * p.z)
            + p.z * m[5] * p.z;
        let field = DVec2::new(self.g[0].dot(p), self.g[1].dot(p)) + self.e;
        let r = pgp + 2.0 * self.ge.dot(p) + self.ee - 2.0 * a.dot(field)
            + a.length_squared() * self.weight;
        if r.is_nan() { f64::MAX } else { r.max(0.0) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> [DVec3; 3] {
        [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(2.0, 0.0, 1.0),
            DVec3::new(0.0, 3.0, 1.0),
        ]
    }

    #[test]
    fn a_triangle_field_reproduces_its_corner_values_and_costs_nothing_there() {
        let p = tri();
        let uv = [
            DVec2::new(0.1, 0.2),
            DVec2::new(0.5, 0.25),
            DVec2::new(0.2, 0.9),
        ];
        let q = AttributeQuadric::of_triangle(p, uv).unwrap();
        assert!((q.weight - 3.0).abs() < 1e-12);
        for k in 0..3 {
            assert!(q.raw(p[k], uv[k]) < 1e-12, "corner {k}");
            // Off the plane the field is unchanged.
            assert!(q.raw(p[k] + DVec3::Z * 5.0, uv[k]) < 1e-12);
        }
        // A value 0.1 away at a corner costs area · 0.1².
        let off = q.raw(p[1], uv[1] + DVec2::new(0.1, 0.0));
        assert!((off - 3.0 * 0.01).abs() < 1e-9, "{off}");
    }

    #[test]
    fn merged_quadrics_add_their_errors() {
        let p = tri();
        let uv = [DVec2::ZERO, DVec2::X, DVec2::Y];
        let a = AttributeQuadric::of_triangle(p, uv).unwrap();
        let b = AttributeQuadric::of_triangle(p.map(|x| x + DVec3::X), uv).unwrap();
        let mut s = a;
        s.add(&b);
        let (x, t) = (DVec3::new(0.7, 0.4, 1.0), DVec2::new(0.3, 0.3));
        assert!((s.raw(x, t) - a.raw(x, t) - b.raw(x, t)).abs() < 1e-12);
        assert!(b.raw(x, t) > 0.0);
    }

    #[test]
    fn degenerate_and_non_finite_triangles_have_no_quadric() {
        let p = tri();
        let uv = [DVec2::ZERO, DVec2::X, DVec2::Y];
        assert!(AttributeQuadric::of_triangle([p[0], p[1], p[0]], uv).is_none());
        let bad = [DVec2::ZERO, DVec2::new(f64::NAN, 0.0), DVec2::Y];
        assert!(AttributeQuadric::of_triangle(p, bad).is_none());
    }
}
