//! Meshes: the file-level [`PolygonMesh`] and the half-edge triangle mesh used for processing.

pub mod polygon;

pub use polygon::{
    Attribute, AttributeData, ElementProperty, ExtraElement, ListProperty, PolygonMesh, ScalarType,
};
