//! The smoothing methods by name, with the options a front end was given: which option applies
//! to which method, what each named value is called, and what a caller who mixes them up is
//! told. The command line and the Python package both translate their syntax into
//! [`SmoothSettings`] and nothing else, so they accept the same options and refuse the same
//! mistakes with the same words.

use super::{
    Boundary, DenoiseOptions, McfOptions, SmoothError, SmoothMethod, TaubinOptions, Variance,
    Weights,
};
use crate::choice::Choice;
use crate::pyramid::PyramidDenoise;

/// A smoothing method by name, without its options.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SmoothKind {
    /// [`SmoothMethod::Auto`].
    #[default]
    Auto,
    /// [`SmoothMethod::Ohtake`] with the [`DenoiseOptions::adaptive`] presets.
    Adaptive,
    /// [`SmoothMethod::Ohtake`] with the [`DenoiseOptions::anisotropic`] presets.
    Anisotropic,
    /// [`SmoothMethod::Taubin`].
    Taubin,
    /// [`SmoothMethod::Mcf`].
    Mcf,
    /// [`SmoothMethod::Pyramid`].
    Pyramid,
}

impl Choice for SmoothKind {
    const WHAT: &'static str = "smoothing method";
    const ALL: &'static [SmoothKind] = &[
        SmoothKind::Auto,
        SmoothKind::Adaptive,
        SmoothKind::Anisotropic,
        SmoothKind::Taubin,
        SmoothKind::Mcf,
        SmoothKind::Pyramid,
    ];

    fn name(self) -> &'static str {
        match self {
            SmoothKind::Auto => "auto",
            SmoothKind::Adaptive => "adaptive",
            SmoothKind::Anisotropic => "anisotropic",
            SmoothKind::Taubin => "taubin",
            SmoothKind::Mcf => "mcf",
            SmoothKind::Pyramid => "pyramid",
        }
    }

    fn about(self) -> &'static str {
        match self {
            SmoothKind::Auto => {
                "The recommended automatic method: the adaptive filter at the local scale of each \
                 face, fitted by local vertex updates, two passes (options as for adaptive)"
            }
            SmoothKind::Adaptive => {
                "Ohtake–Belyaev–Seidel adaptive Gaussian filter of the face normals + vertex \
                 fitting"
            }
            SmoothKind::Anisotropic => {
                "The same on anisotropic neighbourhoods that do not reach across sharp edges"
            }
            SmoothKind::Taubin => "Taubin λ|μ smoothing (explicit; `weights`, `lambda`, `mu`)",
            SmoothKind::Mcf => "Implicit mean-curvature flow (Desbrun et al. 1999; `time_step`)",
            SmoothKind::Pyramid => {
                "Octaves of the detail pyramid attenuated by how far they stand above the noise \
                 the pyramid estimates, with the crease-keeping normal-adaptive operator \
                 (`strength`)"
            }
        }
    }
}

/// What the σ of the Ohtake methods is measured in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterScale {
    /// The mean edge length of the whole mesh.
    Global,
    /// Each face's own edge length, averaged with its neighbours' (for non-uniform sampling).
    Local,
}

impl Choice for FilterScale {
    const WHAT: &'static str = "filter scale";
    const ALL: &'static [FilterScale] = &[FilterScale::Global, FilterScale::Local];

    fn name(self) -> &'static str {
        match self {
            FilterScale::Global => "global",
            FilterScale::Local => "local",
        }
    }

    fn about(self) -> &'static str {
        match self {
            FilterScale::Global => "The mean edge length of the whole mesh",
            FilterScale::Local => "Each face's own edge length (averaged with its neighbours')",
        }
    }
}

impl Choice for Variance {
    const WHAT: &'static str = "variance estimate";
    const ALL: &'static [Variance] = &[Variance::Biased, Variance::Unbiased];

    fn name(self) -> &'static str {
        match self {
            Variance::Biased => "biased",
            Variance::Unbiased => "unbiased",
        }
    }

    fn about(self) -> &'static str {
        match self {
            Variance::Biased => {
                "Weighted variance of the normals (as reconstructed from the paper)"
            }
            Variance::Unbiased => {
                "With the reliability-weights correction (default; see the library docs)"
            }
        }
    }
}

impl Choice for Weights {
    const WHAT: &'static str = "edge weights";
    const ALL: &'static [Weights] = &[
        Weights::Uniform,
        Weights::InverseEdgeLength,
        Weights::Cotangent,
    ];

    fn name(self) -> &'static str {
        match self {
            Weights::Uniform => "uniform",
            Weights::InverseEdgeLength => "inverse-edge",
            Weights::Cotangent => "cotan",
        }
    }

    fn about(self) -> &'static str {
        match self {
            Weights::Uniform => "Equal weights",
            Weights::InverseEdgeLength => "Inverse edge length",
            Weights::Cotangent => "Cotangent weights clamped at zero",
        }
    }
}

impl Choice for Boundary {
    const WHAT: &'static str = "boundary rule";
    const ALL: &'static [Boundary] = &[Boundary::Fixed, Boundary::Smooth];

    fn name(self) -> &'static str {
        match self {
            Boundary::Fixed => "fixed",
            Boundary::Smooth => "smooth",
        }
    }

    fn about(self) -> &'static str {
        match self {
            Boundary::Fixed => "Boundary vertices do not move",
            Boundary::Smooth => {
                "Boundary vertices move (Taubin: along the boundary curve; MCF: natural boundary)"
            }
        }
    }
}

const OHTAKE: &[SmoothKind] = &[
    SmoothKind::Auto,
    SmoothKind::Adaptive,
    SmoothKind::Anisotropic,
];

/// A method named with the options a caller gave; `None` means not given, so the method's
/// default. [`SmoothSettings::method`] turns it into a [`SmoothMethod`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SmoothSettings {
    /// The method.
    pub method: SmoothKind,
    /// Ohtake: ε of the scale selection (× L²); larger smooths more.
    pub epsilon: Option<f64>,
    /// Ohtake: smallest filter scale σ (× L).
    pub sigma_min: Option<f64>,
    /// Ohtake: largest filter scale σ (× L); the work per face grows with its square.
    pub sigma_max: Option<f64>,
    /// Ohtake: number of scales between `sigma_min` and `sigma_max` (1 to 64).
    pub scales: Option<usize>,
    /// Ohtake: anisotropy ρ (0 = isotropic); how much normal differences lengthen distances.
    pub rho: Option<f64>,
    /// Ohtake: where neighbourhoods are cut, in units of σ, in (0, 4] (default: 3 for auto,
    /// else 4, the kernel's support); the work per face grows with its square.
    pub reach: Option<f64>,
    /// Ohtake: variance estimate of the scale selection.
    pub variance: Option<Variance>,
    /// Ohtake: what σ is measured in.
    pub scale: Option<FilterScale>,
    /// Ohtake: fit the vertices with this many rounds of the local vertex update (Sun et al.
    /// 2007) instead of minimising the global energy.
    pub vertex_updates: Option<usize>,
    /// Ohtake: passes of filter-then-fit (default: 2 for auto, else 1).
    pub passes: Option<usize>,
    /// Ohtake: most conjugate-gradient iterations of the vertex fitting.
    pub fit_iterations: Option<usize>,
    /// Ohtake: largest move of a vertex per fitting step (× L).
    pub step_cap: Option<f64>,
    /// Taubin and MCF: iterations (default: 10 for Taubin, 1 for MCF).
    pub iterations: Option<usize>,
    /// Taubin: edge weights (default: cotangent).
    pub weights: Option<Weights>,
    /// Taubin: shrinking factor λ, in (0, 1] (default: 0.5).
    pub lambda: Option<f64>,
    /// Taubin: inflating factor μ, in [-1, 0] (0: plain Laplacian smoothing; default: -0.53).
    pub mu: Option<f64>,
    /// MCF: time step in units of the squared mean edge length L² of the input (default: 1).
    pub time_step: Option<f64>,
    /// Taubin and MCF: what boundary vertices do (default: fixed).
    pub boundary: Option<Boundary>,
    /// Pyramid: how much noise to assume, in units of the estimated noise power (octave gain
    /// 1 − strength / r², r the octave's details over the noise); more removes more (default:
    /// 1).
    pub strength: Option<f64>,
}

impl SmoothSettings {
    /// The name of every option given, with the methods it applies to.
    pub fn given(&self) -> Vec<(&'static str, &'static [SmoothKind])> {
        use SmoothKind::{Mcf, Pyramid, Taubin};
        [
            ("epsilon", self.epsilon.is_some(), OHTAKE),
            ("sigma_min", self.sigma_min.is_some(), OHTAKE),
            ("sigma_max", self.sigma_max.is_some(), OHTAKE),
            ("scales", self.scales.is_some(), OHTAKE),
            ("rho", self.rho.is_some(), OHTAKE),
            ("reach", self.reach.is_some(), OHTAKE),
            ("variance", self.variance.is_some(), OHTAKE),
            ("scale", self.scale.is_some(), OHTAKE),
            ("vertex_updates", self.vertex_updates.is_some(), OHTAKE),
            ("passes", self.passes.is_some(), OHTAKE),
            ("fit_iterations", self.fit_iterations.is_some(), OHTAKE),
            ("step_cap", self.step_cap.is_some(), OHTAKE),
            ("iterations", self.iterations.is_some(), &[Taubin, Mcf]),
            ("weights", self.weights.is_some(), &[Taubin]),
            ("lambda", self.lambda.is_some(), &[Taubin]),
            ("mu", self.mu.is_some(), &[Taubin]),
            ("time_step", self.time_step.is_some(), &[Mcf]),
            ("boundary", self.boundary.is_some(), &[Taubin, Mcf]),
            ("strength", self.strength.is_some(), &[Pyramid]),
        ]
        .into_iter()
        .filter(|&(_, given, _)| given)
        .map(|(name, _, methods)| (name, methods))
        .collect()
    }

    /// The method these settings describe, its options checked: an option of another method
    /// is an error rather than silently ignored, and so is a value out of its range.
    pub fn method(&self) -> Result<SmoothMethod, SmoothError> {
        self.refuse_options_of_other_methods()?;
        let boundary = self.boundary.unwrap_or_default();
        let method = match self.method {
            // Named without options, the recommended method as the library defines it.
            SmoothKind::Auto if self.given().is_empty() => SmoothMethod::Auto,
            SmoothKind::Auto | SmoothKind::Adaptive | SmoothKind::Anisotropic => {
                SmoothMethod::Ohtake(self.denoise_options())
            }
            SmoothKind::Taubin => {
                let d = TaubinOptions::default();
                SmoothMethod::Taubin(TaubinOptions {
                    iterations: self.iterations.unwrap_or(d.iterations),
                    lambda: self.lambda.unwrap_or(d.lambda),
                    mu: self.mu.unwrap_or(d.mu),
                    weights: self.weights.unwrap_or(d.weights),
                    boundary,
                })
            }
            SmoothKind::Mcf => {
                let d = McfOptions::default();
                SmoothMethod::Mcf(McfOptions {
                    iterations: self.iterations.unwrap_or(d.iterations),
                    time_step: self.time_step.unwrap_or(d.time_step),
                    boundary,
                })
            }
            SmoothKind::Pyramid => SmoothMethod::Pyramid(PyramidDenoise {
                strength: self.strength.unwrap_or(PyramidDenoise::default().strength),
            }),
        };
        method.validate()?;
        Ok(method)
    }

    fn refuse_options_of_other_methods(&self) -> Result<(), SmoothError> {
        for (name, methods) in self.given() {
            if !methods.contains(&self.method) {
                let names: Vec<&str> = methods.iter().map(|m| m.name()).collect();
                return Err(SmoothError::InvalidParameter(format!(
                    "{name} does not apply to method {} (it is an option of {})",
                    self.method.name(),
                    names.join(" and ")
                )));
            }
        }
        Ok(())
    }

    /// The Ohtake options (the `adaptive` presets unless the method is `anisotropic` or `auto`).
    fn denoise_options(&self) -> DenoiseOptions {
        let mut o = match self.method {
            SmoothKind::Anisotropic => DenoiseOptions::anisotropic(),
            SmoothKind::Auto => DenoiseOptions::automatic(),
            _ => DenoiseOptions::adaptive(),
        };
        o.epsilon = self.epsilon.unwrap_or(o.epsilon);
        o.sigma_min = self.sigma_min.unwrap_or(o.sigma_min);
        o.sigma_max = self.sigma_max.unwrap_or(o.sigma_max);
        o.scales = self.scales.unwrap_or(o.scales);
        o.rho = self.rho.unwrap_or(o.rho);
        o.reach = self.reach.unwrap_or(o.reach);
        o.variance = self.variance.unwrap_or(o.variance);
        o.max_iterations = self.fit_iterations.unwrap_or(o.max_iterations);
        o.step_cap = self.step_cap.unwrap_or(o.step_cap);
        o.passes = self.passes.unwrap_or(o.passes);
        o.vertex_updates = self.vertex_updates.unwrap_or(o.vertex_updates);
        o.local_scale = self
            .scale
            .map_or(o.local_scale, |s| s == FilterScale::Local);
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_option_of_another_method_is_refused_with_the_methods_it_belongs_to() {
        let settings = SmoothSettings {
            method: SmoothKind::Taubin,
            epsilon: Some(0.1),
            ..SmoothSettings::default()
        };
        let refused = settings.method().expect_err("epsilon is an Ohtake option");
        assert_eq!(
            refused.to_string(),
            "epsilon does not apply to method taubin (it is an option of auto and adaptive and \
             anisotropic)"
        );
    }

    #[test]
    fn auto_without_options_is_the_recommended_method_and_with_options_its_presets() {
        assert_eq!(SmoothSettings::default().method(), Ok(SmoothMethod::Auto));
        let tuned = SmoothSettings {
            passes: Some(3),
            ..SmoothSettings::default()
        };
        let mut expected = DenoiseOptions::automatic();
        expected.passes = 3;
        assert_eq!(tuned.method(), Ok(SmoothMethod::Ohtake(expected)));
    }

    #[test]
    fn values_out_of_range_are_refused() {
        let settings = SmoothSettings {
            method: SmoothKind::Adaptive,
            scales: Some(0),
            ..SmoothSettings::default()
        };
        assert!(settings.method().is_err());
    }
}
