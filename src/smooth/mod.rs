//! Denoising of triangle meshes.
//!
//! Ohtake–Belyaev–Seidel feature-preserving smoothing ([`denoise`]): an adaptive (or
//! anisotropic) Gaussian filter of the face normals followed by fitting the vertices to them.
//! One algorithm concept per file: [`kernel`], [`dual`] (geodesic neighbourhoods),
//! [`normal_filter`] (scale selection and smoothed normals), [`fitting`] (vertex update),
//! [`surface`] (flat arrays), [`ohtake`] (the pipeline).

pub mod dual;
pub mod fitting;
pub mod kernel;
pub mod normal_filter;
pub mod ohtake;
pub mod surface;

pub use ohtake::{DenoiseOptions, Denoised, SmoothError, denoise};
