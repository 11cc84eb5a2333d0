//! Numerics shared by the cascadic subdivider ([`crate::subdiv`]) and the implicit
//! mean-curvature-flow smoother ([`crate::smooth`]), below both as the finite-element Laplacian
//! is below the algorithms that use it:
//! - [`fem`]: linear finite elements on flat arrays — lumped mass, cotangent stiffness, the
//!   system matrix `M + αL`, in symmetric CSR form;
//! - `solvers`: damped Jacobi, preconditioned conjugate gradients and the exact solve of
//!   those systems.

pub mod fem;
pub(crate) mod solvers;
