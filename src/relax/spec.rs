//! The operators by name and with their parameters: [`RelaxKind`] is what `--relax` chooses,
//! [`RelaxationSpec`] what a `.pyr` file records, so that a loader rebuilds the very operator
//! the pyramid was analysed with.
//!
//! [`RelaxationSpec`] is serialised into the `META` section (`formats/pyr.md`): its variant
//! order and its field names and order are part of the file format.

use super::{MeanCurvatureStep, NormalAdaptive, NormalAverage, Relaxation, SecondDifference};
use crate::choice::{Choice, UnknownChoice};
use serde::{Deserialize, Serialize};

/// An operator without its parameters: the values of the command line's `--relax`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RelaxKind {
    /// Guskov's non-uniform second-difference operator.
    #[default]
    SecondDifference,
    /// One Jacobi step of implicit mean-curvature motion (cotangent weights, lumped mass).
    Mcm,
    /// Guskov's operator with hinges weighted by the agreement of their normals (from the
    /// input denoised by Ohtake's filter), so that predictions keep creases.
    Normal,
}

/// The values of `--relax`, by the names of their operators ([`RelaxationSpec::name`]).
impl Choice for RelaxKind {
    const WHAT: &'static str = "relaxation";
    const ALL: &'static [RelaxKind] = &[
        RelaxKind::SecondDifference,
        RelaxKind::Mcm,
        RelaxKind::Normal,
    ];

    fn name(self) -> &'static str {
        self.spec().name()
    }

    fn about(self) -> &'static str {
        match self {
            RelaxKind::SecondDifference => "Guskov's non-uniform second-difference operator",
            RelaxKind::Mcm => {
                "One Jacobi step of implicit mean-curvature motion (cotangent weights, lumped mass)"
            }
            RelaxKind::Normal => {
                "Guskov's operator with hinges weighted by the agreement of their normals (from \
                 the input denoised by Ohtake's filter), so that predictions keep creases"
            }
        }
    }
}

impl RelaxKind {
    /// The operator of this kind with its default parameters.
    pub fn spec(self) -> RelaxationSpec {
        match self {
            RelaxKind::SecondDifference => SecondDifference::default().into(),
            RelaxKind::Mcm => MeanCurvatureStep::default().into(),
            RelaxKind::Normal => NormalAdaptive::default().into(),
        }
    }
}

/// A kind by its name ([`Choice::parse`]).
impl std::str::FromStr for RelaxKind {
    type Err = UnknownChoice;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        RelaxKind::parse(name)
    }
}

/// The relaxation operator the pyramid is analysed with, with its options.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum RelaxationSpec {
    /// Guskov's second-difference operator.
    SecondDifference {
        /// [`SecondDifference::degenerate_area_ratio`].
        degenerate_area_ratio: f64,
    },
    /// One Jacobi step of implicit mean-curvature motion ([`MeanCurvatureStep`]).
    MeanCurvature {
        /// [`MeanCurvatureStep::width`].
        width: f64,
        /// [`MeanCurvatureStep::damping`].
        damping: f64,
    },
    /// The 1-ring average of format 2.0's `--relax normal` ([`NormalAverage`]); files that
    /// name it still load with it, `--relax` no longer offers it.
    NormalAverage {
        /// [`NormalAverage::normal_scale`].
        normal_scale: f64,
    },
    /// Guskov's operator steered by normals ([`NormalAdaptive`]); the pyramid gives it its
    /// guide (the finest level denoised by `smooth --method auto`).
    NormalAdaptive {
        /// [`NormalAdaptive::normal_scale`].
        normal_scale: f64,
        /// [`NormalAdaptive::degenerate_area_ratio`].
        degenerate_area_ratio: f64,
    },
}

/// The default operator: [`RelaxKind::default`] with its default parameters.
impl Default for RelaxationSpec {
    fn default() -> Self {
        RelaxKind::default().spec()
    }
}

impl From<SecondDifference> for RelaxationSpec {
    fn from(op: SecondDifference) -> Self {
        RelaxationSpec::SecondDifference {
            degenerate_area_ratio: op.degenerate_area_ratio,
        }
    }
}

impl From<MeanCurvatureStep> for RelaxationSpec {
    fn from(op: MeanCurvatureStep) -> Self {
        RelaxationSpec::MeanCurvature {
            width: op.width,
            damping: op.damping,
        }
    }
}

impl From<NormalAverage> for RelaxationSpec {
    fn from(op: NormalAverage) -> Self {
        RelaxationSpec::NormalAverage {
            normal_scale: op.normal_scale,
        }
    }
}

/// The operator's options; its guide is not part of the spec (the pyramid recomputes it).
impl From<NormalAdaptive> for RelaxationSpec {
    fn from(op: NormalAdaptive) -> Self {
        RelaxationSpec::NormalAdaptive {
            normal_scale: op.normal_scale,
            degenerate_area_ratio: op.degenerate_area_ratio,
        }
    }
}

impl RelaxationSpec {
    /// The operator (the normal-adaptive one without a guide: it takes its normals from the
    /// parameter geometry; [`Pyramid`](crate::Pyramid) gives it a denoised guide).
    pub fn operator(&self) -> Box<dyn Relaxation> {
        match *self {
            RelaxationSpec::SecondDifference {
                degenerate_area_ratio,
            } => Box::new(SecondDifference {
                degenerate_area_ratio,
            }),
            RelaxationSpec::MeanCurvature { width, damping } => {
                Box::new(MeanCurvatureStep { width, damping })
            }
            RelaxationSpec::NormalAverage { normal_scale } => {
                Box::new(NormalAverage { normal_scale })
            }
            RelaxationSpec::NormalAdaptive {
                normal_scale,
                degenerate_area_ratio,
            } => Box::new(NormalAdaptive {
                normal_scale,
                degenerate_area_ratio,
                ..NormalAdaptive::default()
            }),
        }
    }

    /// The operator's command-line name (`second-difference`, `mcm`, `normal`; `normal-average`
    /// for the operator of format 2.0's `--relax normal`).
    pub fn name(&self) -> &'static str {
        self.operator().name()
    }

    /// `None` when every option is in its valid range, else what is wrong (a file could hold
    /// anything).
    pub(crate) fn invalid(&self) -> Option<&'static str> {
        let ok = match *self {
            RelaxationSpec::SecondDifference {
                degenerate_area_ratio,
            } => (0.0..1.0).contains(&degenerate_area_ratio),
            RelaxationSpec::MeanCurvature { width, damping } => {
                width > 0.0 && width.is_finite() && damping > 0.0 && damping <= 1.0
            }
            RelaxationSpec::NormalAverage { normal_scale } => {
                normal_scale > 0.0 && normal_scale.is_finite()
            }
            RelaxationSpec::NormalAdaptive {
                normal_scale,
                degenerate_area_ratio,
            } => {
                normal_scale > 0.0
                    && normal_scale.is_finite()
                    && (0.0..1.0).contains(&degenerate_area_ratio)
            }
        };
        (!ok).then_some("relaxation options out of range")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_is_guskovs_operator_with_its_defaults() {
        assert_eq!(
            RelaxationSpec::default(),
            RelaxationSpec::SecondDifference {
                degenerate_area_ratio: SecondDifference::default().degenerate_area_ratio
            }
        );
    }

    #[test]
    fn files_keep_their_operators_variant_numbers() {
        // META stores the variant index first: 2.0 files name the 1-ring average with 2, and
        // the steered operator came after it as 3.
        let index = |spec: RelaxationSpec| {
            bincode::serde::encode_to_vec(spec, bincode::config::standard()).expect("encodes")[0]
        };
        assert_eq!(index(SecondDifference::default().into()), 0);
        assert_eq!(index(MeanCurvatureStep::default().into()), 1);
        assert_eq!(index(NormalAverage::default().into()), 2);
        assert_eq!(index(RelaxKind::Normal.spec()), 3);
        assert_eq!(NormalAverage::default().name(), "normal-average");
        let round_trip = |spec: RelaxationSpec| {
            let bytes = bincode::serde::encode_to_vec(spec, bincode::config::standard()).unwrap();
            let (back, _): (RelaxationSpec, usize) =
                bincode::serde::decode_from_slice(&bytes, bincode::config::standard()).unwrap();
            back
        };
        for kind in RelaxKind::ALL {
            assert_eq!(round_trip(kind.spec()), kind.spec());
        }
    }
}
