//! Distances below floating-point rounding, shown as what they are: zero.

use super::error::Comparison;

/// Distances below this fraction of the bounding-box diagonal are rounding noise: closest-point
/// queries on the same triangle in a different order land a few ulps of the coordinates apart
/// (a Hausdorff of 3e-17 between a file and itself).
pub const ROUNDING_NOISE: f64 = 64.0 * f64::EPSILON;

impl Comparison {
    /// The comparison with every distance below [`ROUNDING_NOISE`] times the bounding-box
    /// diagonal set to exactly 0 (and its relative value with it), so identical meshes compare
    /// as 0 rather than as 1e-17.
    pub fn without_rounding_noise(self) -> Comparison {
        let noise = ROUNDING_NOISE * self.bbox_diagonal;
        let snap = |d: f64| if d.abs() <= noise { 0.0 } else { d };
        let mut c = self;
        c.e_v = snap(c.e_v);
        c.hausdorff = snap(c.hausdorff);
        c.hausdorff_result_to_reference = snap(c.hausdorff_result_to_reference);
        c.hausdorff_reference_to_result = snap(c.hausdorff_reference_to_result);
        if c.e_v == 0.0 {
            c.e_v_rel = 0.0;
            c.e_v_over_l = 0.0;
        }
        if c.hausdorff == 0.0 {
            c.hausdorff_rel = 0.0;
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn comparison(e_v: f64, hausdorff: f64) -> Comparison {
        Comparison {
            e_v,
            e_n: 0.0,
            hausdorff,
            hausdorff_result_to_reference: hausdorff,
            hausdorff_reference_to_result: hausdorff / 2.0,
            e_v_rel: e_v / 2.0,
            e_n_rel: 0.0,
            hausdorff_rel: hausdorff / 2.0,
            bbox_diagonal: 2.0,
            mean_edge_length: 0.1,
            e_v_over_l: e_v / 0.1,
        }
    }

    #[test]
    fn distances_within_rounding_of_the_diagonal_become_zero() {
        let c = comparison(1e-17, 2.86e-17).without_rounding_noise();
        assert_eq!(
            (c.e_v, c.e_v_rel, c.e_v_over_l, c.hausdorff, c.hausdorff_rel),
            (0.0, 0.0, 0.0, 0.0, 0.0)
        );
        assert_eq!(c.hausdorff_reference_to_result, 0.0);
    }

    #[test]
    fn distances_above_rounding_stay_as_they_are() {
        let c = comparison(1e-9, 1e-6);
        assert_eq!(c.without_rounding_noise(), c);
    }
}
