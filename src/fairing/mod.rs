//! The smoothing (denoising) filters of noisy scans, keeping the connectivity: every smoother
//! is a plain function over a [`Mesh`](crate::mesh::Mesh) that returns new positions indexed
//! like [`Mesh::positions`](crate::mesh::Mesh::positions) (vertex slot order). They sit below
//! the detail pyramid, which smooths the guide of its normal-adaptive operator with
//! [`denoise`]; the door that chooses a method by name, the pyramid's own among them, is
//! [`crate::smooth`], above both.
//!
//! - Ohtake–Belyaev–Seidel feature-preserving smoothing ([`denoise`]): an adaptive (or
//!   anisotropic) Gaussian filter of the face normals followed by fitting the vertices to them.
//!   One concept per file: `kernel`, `dual` (geodesic neighbourhoods), `normal_filter`
//!   (scale selection and smoothed normals), `fitting` (vertex update), `surface` (flat
//!   arrays), `ohtake` (the pipeline).
//! - Baselines from the paper's comparisons (`docs/algorithms.md` §2, §5): `taubin` (λ|μ smoothing
//!   with uniform, inverse-edge-length or cotangent weights) and `mcf` (implicit
//!   mean-curvature flow, Desbrun et al. 1999).
//!
//! Measure results with [`crate::metrics::compare`] (E_v, E_n, Hausdorff).

pub(crate) mod dual;
pub(crate) mod fitting;
pub(crate) mod kernel;
pub(crate) mod mcf;
pub(crate) mod normal_filter;
pub(crate) mod ohtake;
pub(crate) mod surface;
pub(crate) mod taubin;
#[cfg(test)]
mod testutil;

pub use fitting::FitReport;
pub use mcf::{McfOptions, implicit_mcf};
pub use normal_filter::Variance;
pub use ohtake::{DenoiseOptions, Denoised, denoise};
pub use taubin::{TaubinOptions, Weights, taubin_smoothing};

/// What the smoothers do with boundary vertices (those on a hole's rim).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Boundary {
    /// Boundary vertices stay where they are. Safe on open scans (the rim does not shrink), at
    /// the price of leaving noise on the rim itself.
    #[default]
    Fixed,
    /// Boundary vertices move too: Taubin smooths them along the boundary curve (only their
    /// two boundary neighbours count), MCF uses natural boundary conditions (the rim follows
    /// the flow of the surface). Rims shrink slowly, as any curve smoothing does.
    Smooth,
}

/// Why smoothing could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SmoothError {
    /// The input holds no surface (nothing at all, a point cloud, only degenerate faces).
    #[error(transparent)]
    NoSurface(#[from] crate::mesh::MissingSurface),
    /// The input cannot be turned into a half-edge mesh.
    #[error(transparent)]
    Build(#[from] crate::mesh::BuildError),
    /// A parameter is out of its range.
    #[error("{0}")]
    InvalidParameter(String),
    /// The progressive mesh or the detail pyramid of the pyramid method
    /// (`meshpyr::smooth::SmoothMethod::Pyramid`) could not be built.
    #[error("building the detail pyramid: {0}")]
    Pyramid(String),
    /// A vertex position is NaN or infinite.
    #[error("vertex {0} has a non-finite coordinate")]
    NonFinite(usize),
    /// The linear solve of an implicit step failed.
    #[error("linear solve of iteration {iteration}: {reason}")]
    Solver {
        /// 1-based iteration.
        iteration: usize,
        /// What the solver reported.
        reason: String,
    },
}
