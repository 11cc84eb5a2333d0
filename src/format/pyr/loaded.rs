//! What a decoded file gives besides its hierarchy: whether its stored details fit it, the
//! repaired mesh on demand, and its parts for the pyramid layer, which turns them into a
//! `Pyramid` (`crate::pyramid`, module `loaded`).

use super::details::{ANALYSIS_VERSION, DetailSection};
use super::{BASE, PyrData, SPLT, corrupt};
use super::{PyramidOptions, StoredDetails};
use crate::format::FormatError;
use crate::format::container::Container;
use crate::mesh::{Built, Mesh, PolygonMesh, SourceMap};
use crate::pm::ProgressiveMesh;

/// The details a `.pyr` file stores (section `DETL`).
#[derive(Clone, Debug)]
pub enum FileDetails {
    /// The file has none (format 2.0 or older, or written without details).
    Absent,
    /// Details analysed on this very hierarchy by this version of the analysis.
    Stored(StoredDetails),
    /// Details this reader cannot use, and why (analysed on another hierarchy, or by another
    /// version of the analysis).
    Unusable(String),
}

impl PyrData {
    /// The repaired half-edge mesh of [`Self::input`] and its map back (the one `build` made;
    /// deterministic), built on demand.
    pub fn built(&self) -> Result<Built, FormatError> {
        Mesh::from_polygons(&self.input).map_err(|e| corrupt(0, e.to_string()))
    }

    /// The input, where each vertex of its repaired mesh came from, the hierarchy and the build
    /// options: what a pyramid is made of besides its details.
    pub(crate) fn into_scan_parts(
        self,
    ) -> (PolygonMesh, SourceMap, ProgressiveMesh, PyramidOptions) {
        let source = self.source.unwrap_or_else(|| identity_source(&self.input));
        (self.input, source, self.pm, self.info)
    }

    /// Level `level` of the hierarchy with everything of the input a level keeps: per-vertex
    /// attributes, each face's attributes, material and groups, and, when the hierarchy kept
    /// the texture seams ([`ProgressiveMesh::keeps_seams`]), each corner's texture
    /// coordinates and other per-corner data (`crate::pm::level_mesh`; the same bytes as the
    /// level of the hierarchy in memory). Without kept seams the corners' data is left out.
    pub fn level_mesh(&self, level: usize) -> Result<PolygonMesh, FormatError> {
        let identity;
        let source = match &self.source {
            Some(s) => s,
            None => {
                identity = identity_source(&self.input);
                &identity
            }
        };
        crate::pm::level_mesh(&self.pm, &self.input, source, level)
            .map_err(|e| corrupt(0, e.to_string()))
    }
}

/// The map of an input that needed no repair: a file loaded without building the half-edge
/// mesh (see `clean_triangle_faces`) has the input itself as its mesh, vertex for vertex and
/// face for face.
fn identity_source(input: &PolygonMesh) -> SourceMap {
    SourceMap {
        vertex_source: (0..input.positions.len() as u32).collect(),
        face_source: (0..input.n_faces() as u32).collect(),
        input_vertices: input.positions.len(),
    }
}

/// Whether a decoded `DETL` section fits the file: analysed on its `BASE` and `SPLT` by this
/// version of the analysis.
pub(super) fn file_details(c: &Container<'_>, detl: Option<DetailSection>) -> FileDetails {
    let Some(d) = detl else {
        return FileDetails::Absent;
    };
    let crc = |tag| c.entry(tag).map_or(0, |e| e.crc);
    if d.analysis_version != ANALYSIS_VERSION {
        FileDetails::Unusable(format!(
            "the stored ones come from analysis version {} (this is {ANALYSIS_VERSION})",
            d.analysis_version
        ))
    } else if d.hierarchy_crcs != [crc(BASE), crc(SPLT)] {
        FileDetails::Unusable("the stored ones were analysed on another hierarchy".into())
    } else {
        match d.stored {
            Ok(stored) => FileDetails::Stored(stored),
            Err(why) => FileDetails::Unusable(why),
        }
    }
}
