//! The finite-support Gaussian-like kernel of Ohtake–Belyaev–Seidel (`docs/algorithms.md` §2.1).
//!
//! ```text
//! K_σ(x) = 1/(√(2π) σ) · { exp(−x²/(2σ²))            |x| ≤ 2σ
//!                          (4 − |x|/σ)⁴ / (16 e²)      2σ < |x| ≤ 4σ
//!                          0                           |x| > 4σ }
//! ```
//!
//! The quartic tail matches the Gaussian's value, slope and curvature at 2σ and vanishes with
//! its first two derivatives at 4σ, so the kernel is C² with support [−4σ, 4σ].

/// Support radius of the kernel in units of σ: `K_σ(x) = 0` for `|x| ≥ 4σ`.
pub(crate) const SUPPORT: f64 = 4.0;

/// Where the Gaussian hands over to the quartic tail, in units of σ.
const JOIN: f64 = 2.0;

/// 1 / (16 e²): the quartic tail's coefficient, fixed by matching the Gaussian at 2σ.
const TAIL: f64 = 1.0 / (16.0 * std::f64::consts::E * std::f64::consts::E);

/// The kernel's shape without the normalisation, as a function of `t = |x| / σ`:
/// `exp(−t²/2)` up to 2, `(4 − t)⁴/(16e²)` up to 4, then 0.
///
/// The normalisation 1/(√(2π)σ) cancels wherever all weights share one σ (the smoothed
/// normal and its variance), so the filter uses this directly.
#[inline]
pub(crate) fn shape(t: f64) -> f64 {
    let t = t.abs();
    if t <= JOIN {
        (-0.5 * t * t).exp()
    } else if t < SUPPORT {
        let r = SUPPORT - t;
        let r2 = r * r;
        TAIL * r2 * r2
    } else {
        0.0
    }
}

/// The normalised kernel `K_σ(x)`. A non-positive or non-finite `sigma` gives 0.
#[inline]
#[cfg(test)]
pub(crate) fn kernel(x: f64, sigma: f64) -> f64 {
    if !(sigma > 0.0 && sigma.is_finite()) {
        return 0.0;
    }
    shape(x / sigma) / ((2.0 * std::f64::consts::PI).sqrt() * sigma)
}

/// Samples per unit of `t` in [`ShapeTable`].
const TABLE_DENSITY: usize = 512;

/// [`shape`] tabulated on `[0, 4]` for the filter's inner loop, linearly interpolated: an
/// `exp` per neighbour and scale dominates the sweep otherwise. The interpolation error is
/// below 1e-6 (h²/8 · max|shape''| with h = 1/512), far under the noise being filtered; the
/// table is exactly 0 from 4 on, so the support is unchanged.
pub(crate) struct ShapeTable {
    values: Vec<f64>,
}

impl ShapeTable {
    /// The table (about 16 kB).
    pub(crate) fn new() -> ShapeTable {
        let n = SUPPORT as usize * TABLE_DENSITY;
        // One extra sample past the end so interpolation never reads out of bounds.
        let values = (0..=n + 1)
            .map(|i| shape(i as f64 / TABLE_DENSITY as f64))
            .collect();
        ShapeTable { values }
    }

    /// `shape(t)` for `t ≥ 0` (interpolated; 0 from the support on).
    #[inline]
    pub(crate) fn eval(&self, t: f64) -> f64 {
        if t.is_nan() || t >= SUPPORT {
            return 0.0;
        }
        let x = t.max(0.0) * TABLE_DENSITY as f64;
        let i = x as usize;
        let f = x - i as f64;
        let a = self.values[i];
        let b = self.values[i + 1];
        a + f * (b - a)
    }
}

impl Default for ShapeTable {
    fn default() -> Self {
        ShapeTable::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One-sided derivatives by finite differences on both sides of `x0`.
    fn one_sided(f: impl Fn(f64) -> f64, x0: f64, h: f64) -> [(f64, f64); 3] {
        let left = [f(x0 - h), f(x0 - 2.0 * h), f(x0 - 3.0 * h)];
        let right = [f(x0 + h), f(x0 + 2.0 * h), f(x0 + 3.0 * h)];
        [
            (f(x0 - 1e-12), f(x0 + 1e-12)),
            ((f(x0) - left[0]) / h, (right[0] - f(x0)) / h),
            (
                (f(x0) - 2.0 * left[0] + left[1]) / (h * h),
                (right[1] - 2.0 * right[0] + f(x0)) / (h * h),
            ),
        ]
    }

    #[test]
    fn c2_at_the_join_and_zero_at_the_support() {
        let s = 0.7;
        let k = |x: f64| kernel(x, s);
        let [v, d1, d2] = one_sided(k, 2.0 * s, 1e-5);
        assert!((v.0 - v.1).abs() < 1e-10, "{v:?}");
        assert!((d1.0 - d1.1).abs() < 1e-3, "{d1:?}");
        assert!((d2.0 - d2.1).abs() < 2e-2, "{d2:?}");
        // The values from the reference: K, K', K'' at 2σ for σ = 0.7.
        assert!((v.0 - 0.07713).abs() < 1e-5, "{}", v.0);
        assert!((d1.0 + 0.22037).abs() < 1e-3, "{}", d1.0);
        assert!((d2.0 - 0.472).abs() < 1e-2, "{}", d2.0);
        let [v, d1, d2] = one_sided(k, 4.0 * s, 1e-4);
        assert_eq!(v.1, 0.0);
        assert!(v.0.abs() < 1e-12 && d1.0.abs() < 1e-9 && d2.0.abs() < 1e-4);
        assert_eq!(kernel(4.0 * s, s), 0.0);
        assert_eq!(kernel(10.0, s), 0.0);
    }

    #[test]
    fn the_table_follows_the_shape() {
        let table = ShapeTable::new();
        let mut worst = 0.0f64;
        for i in 0..=50_000 {
            let t = i as f64 * 5.0 / 50_000.0;
            worst = worst.max((table.eval(t) - shape(t)).abs());
        }
        assert!(worst < 1e-6, "{worst}");
        assert_eq!(table.eval(0.0), 1.0);
        assert_eq!(table.eval(4.0), 0.0);
        assert_eq!(table.eval(f64::NAN), 0.0);
    }

    #[test]
    fn the_quartic_tail_is_a_poor_mans_gaussian() {
        // Without the tail's exact coefficient the pieces would disagree at 2σ (the C4 bug).
        assert!((shape(2.0) - (-2.0f64).exp()).abs() < 1e-15);
        assert!((shape(2.0 + 1e-9) - shape(2.0)).abs() < 1e-9);
        assert_eq!(shape(-1.3), shape(1.3));
        assert_eq!(kernel(1.0, 0.0), 0.0);
        assert_eq!(kernel(1.0, f64::NAN), 0.0);
        // Integrates to about 1 (the tail adds a little mass over the Gaussian's 2σ cut).
        let s = 1.3;
        let n = 20000;
        let h = 8.0 * s / n as f64;
        let integral: f64 = (0..n)
            .map(|i| kernel(-4.0 * s + (i as f64 + 0.5) * h, s) * h)
            .sum();
        assert!((integral - 1.0).abs() < 0.02, "{integral}");
    }
}
