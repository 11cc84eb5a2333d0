//! # meshpyr
//!
//! A multiresolution mesh editing engine built on a progressive-mesh hierarchy.
//!
//! Modules, one concept each: [`mesh`] (file-level polygons and the half-edge mesh),
//! [`io`] (OBJ/PLY/OFF/STL), [`pm`] (the progressive mesh), [`relax`] (relaxation operators),
//! [`smooth`] (denoising), [`metrics`] (error metrics and curvature), and `cli` (the
//! `meshpyr` command line; the default feature `cli`, without which the library depends on no
//! argument parser, progress bar or error-report crate).
#![warn(missing_docs)]

#[cfg(feature = "cli")]
pub mod cli;
pub mod format;
#[doc(hidden)]
pub mod fuzzing;
pub mod io;
pub mod mesh;
pub mod metrics;
pub mod numerics;
pub mod plot;
pub mod pm;
pub mod progress;
pub mod pyramid;
pub mod relax;
pub mod render;
pub mod smooth;
pub mod subdiv;
