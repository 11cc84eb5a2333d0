//! Mesh smoothing (denoising) of noisy scans by any method, chosen by name: [`smooth_mesh`]
//! runs a [`SmoothMethod`] on a mesh as read from a file, and [`SmoothSettings`] names a method
//! and the options a front end was given, and says which option applies to which method.
//!
//! The smoothers themselves (Ohtake–Belyaev–Seidel's [`denoise`], [`taubin_smoothing`],
//! [`implicit_mcf`]) live in the `fairing` module, below the detail pyramid, and are
//! re-exported here; the pyramid's own method ([`crate::pyramid::pyramid_denoise`]) is
//! dispatched here, above both.
//!
//! Measure results with [`crate::metrics::compare`] (E_v, E_n, Hausdorff).

mod flat;
pub(crate) mod method;
mod settings;

pub use crate::fairing::{
    Boundary, DenoiseOptions, Denoised, FitReport, McfOptions, SmoothError, TaubinOptions,
    Variance, Weights, denoise, implicit_mcf, taubin_smoothing,
};
pub use method::{SmoothMethod, Smoothed, smooth_mesh, smooth_mesh_owned, smooth_positions};
pub use settings::{FilterScale, SmoothKind, SmoothSettings};
