//! Measurements on meshes.

pub mod curvature;
pub(crate) mod distance;
pub(crate) mod error;
mod field;
mod rounding;

pub use error::{CompareError, Comparison};
pub use error::{Reference, Surface, compare};
pub use field::{FieldPercentiles, vertex_distances};
pub use rounding::ROUNDING_NOISE;
