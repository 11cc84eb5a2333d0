//! Meshes: the file-level [`PolygonMesh`] and the half-edge triangle [`Mesh`] used for
//! processing, with the builder that turns one into the other.

pub mod build;
pub mod geometry;
pub mod halfedge;
pub mod polygon;
pub mod prune;
pub mod shapes;
pub mod topology;
mod union_find;
pub mod validate;

pub use build::{BuildError, BuildReport, Built, CornerTable, Repaired, SourceMap};
pub use geometry::{BoundingBox, cotangent};
pub use halfedge::{FaceId, HalfedgeId, Mesh, Outgoing, SlotIndex, VertexId};
pub use polygon::{
    Attribute, AttributeData, ElementProperty, ExtraElement, ListProperty, PolygonMesh, ScalarType,
};
pub use prune::{Pruned, prune_small_components};
pub use topology::Topology;
pub use validate::ValidationError;
