//! Measurements on meshes.

pub mod curvature;
