//! Meshes: the file-level [`PolygonMesh`] and the half-edge triangle [`Mesh`] used for
//! processing, with the builder that turns one into the other.

pub(crate) mod build;
pub mod corners;
pub(crate) mod geometry;
pub(crate) mod halfedge;
pub(crate) mod info;
mod normals;
pub(crate) mod polygon;
mod prune;
pub mod shapes;
mod surface;
mod texture_info;
pub(crate) mod topology;
mod union_find;
pub(crate) mod validate;

pub use build::BuildReport;
pub(crate) use build::CornerTable;
pub use build::{BuildError, Built, SourceMap};
pub use corners::{CornerAttribute, Material, Materials, NO_VALUE};
pub use geometry::BoundingBox;
pub use geometry::cotangent;
pub use halfedge::{FaceId, HalfedgeId};
pub use halfedge::{Mesh, SlotIndex, VertexId};
pub use info::MeshInfo;
pub use polygon::{
    Attribute, AttributeData, ElementProperty, ExtraElement, ListProperty, PolygonMesh, ScalarType,
};
pub use prune::{Pruned, prune_small_components};
pub use surface::MissingSurface;
pub use texture_info::TextureInfo;
pub use topology::Topology;
pub use validate::ValidationError;
