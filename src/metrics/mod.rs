//! Measurements on meshes.

pub mod curvature;
pub mod distance;
pub mod error;

pub use distance::{Closest, TriangleBvh, closest_point_on_triangle};
pub use error::{CompareError, Comparison, Reference, Surface, compare};
