//! Simplification as a front end asks for it: exactly one target among a face count, a ratio
//! and an error, and optionally the small pieces to drop first. A ratio refers to the mesh as
//! given, not to what is left after pruning, so that `--ratio 0.1 --prune …` keeps a tenth of
//! the file's triangles.

use super::progressive::PmOptions;
use super::simplify::{Simplified, SimplifyError, SimplifyTarget, simplify};
use crate::mesh::{PolygonMesh, Pruned, prune_small_components};
use crate::progress::Progress;

/// Where to stop simplifying, and what to drop before starting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimplifyGoal {
    /// When to stop.
    pub target: SimplifyTarget,
    /// Drop the connected pieces whose bounding-box diagonal is below this fraction of the
    /// whole mesh's first ([`prune_small_components`]); `None` keeps every piece.
    pub prune: Option<f64>,
}

impl SimplifyGoal {
    /// The goal with exactly one of `faces`, `ratio` and `error` given (an error otherwise),
    /// and `prune`, checked to be a fraction in [0, 1].
    pub fn one_of(
        faces: Option<usize>,
        ratio: Option<f64>,
        error: Option<f64>,
        prune: Option<f64>,
    ) -> Result<SimplifyGoal, SimplifyError> {
        let target = match (faces, ratio, error) {
            (Some(n), None, None) => SimplifyTarget::Faces(n),
            (None, Some(r), None) => SimplifyTarget::Ratio(r),
            (None, None, Some(e)) => SimplifyTarget::Error(e),
            _ => {
                return Err(SimplifyError::InvalidTarget(
                    "give exactly one of faces (a triangle count), ratio (a fraction in (0, 1]) \
                     or error (a fraction of the bounding-box diagonal)"
                        .to_string(),
                ));
            }
        };
        if let Some(fraction) = prune {
            check_prune(fraction)?;
        }
        Ok(SimplifyGoal { target, prune })
    }
}

fn check_prune(fraction: f64) -> Result<(), SimplifyError> {
    if (0.0..=1.0).contains(&fraction) {
        return Ok(());
    }
    Err(SimplifyError::InvalidTarget(format!(
        "prune must be a fraction in [0, 1], got {fraction}"
    )))
}

/// [`simplify`] towards `goal`: its small pieces pruned first if asked (what was dropped is
/// returned with the result), then simplified to its target.
pub fn simplify_to_goal(
    input: &PolygonMesh,
    goal: &SimplifyGoal,
    opts: &PmOptions,
    progress: &dyn Progress,
) -> Result<(Simplified, Option<Pruned>), SimplifyError> {
    let Some(fraction) = goal.prune else {
        return Ok((simplify(input, goal.target, opts, progress)?, None));
    };
    check_prune(fraction)?;
    let target = match goal.target {
        SimplifyTarget::Ratio(r) if r > 0.0 && r <= 1.0 => {
            SimplifyTarget::Faces((r * input.n_triangles() as f64).round() as usize)
        }
        other => other,
    };
    let (kept, pruned) = prune_small_components(input, fraction);
    Ok((simplify(&kept, target, opts, progress)?, Some(pruned)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exactly_one_target_and_a_fraction_to_prune() {
        assert!(SimplifyGoal::one_of(Some(10), Some(0.5), None, None).is_err());
        assert!(SimplifyGoal::one_of(None, None, None, None).is_err());
        let refused = SimplifyGoal::one_of(Some(10), None, None, Some(1.5)).expect_err("range");
        assert_eq!(
            refused.to_string(),
            "invalid target: prune must be a fraction in [0, 1], got 1.5"
        );
        let goal = SimplifyGoal::one_of(None, Some(0.5), None, Some(0.1)).expect("valid");
        assert_eq!(goal.target, SimplifyTarget::Ratio(0.5));
    }
}
