//! File-level glue: a polygon mesh as read from a file → half-edge mesh (repaired) →
//! progressive mesh → detail pyramid, and back to a polygon mesh with **exactly the input's
//! vertices and faces in the same order** (attributes untouched), so per-vertex data still
//! lines up after filtering.

use super::{Pyramid, PyramidError};
use crate::mesh::{Mesh, PolygonMesh, SourceMap};
use crate::pm::{PmOptions, ProgressiveMesh};
use crate::progress::Progress;
use crate::relax::Relaxation;
use glam::DVec3;

/// Options for building a [`ScanPyramid`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PyramidOptions {
    /// How the progressive mesh is built (defaults: collapse as far as legal).
    pub pm: PmOptions,
}

/// A scan with its progressive mesh and detail pyramid.
pub struct ScanPyramid {
    /// The mesh as read.
    pub input: PolygonMesh,
    /// Where each vertex of the repaired mesh came from in the input. The repaired half-edge
    /// mesh itself is dropped once the hierarchy is built: filters never read it, and it is
    /// about 430 B per vertex, which would sit through the analysis' memory peak.
    pub source: SourceMap,
    /// The hierarchy.
    pub pm: ProgressiveMesh,
    /// The pyramid of the input's positions.
    pub pyramid: Pyramid,
}

impl ScanPyramid {
    /// Builds everything; `progress` runs 0 → 0.5 for the PM and 0.5 → 1 for the analysis.
    pub fn build(
        input: PolygonMesh,
        relaxation: &dyn Relaxation,
        options: &PyramidOptions,
        progress: &dyn Progress,
    ) -> Result<ScanPyramid, PyramidError> {
        let built = Mesh::from_polygons(&input)?;
        let pm =
            ProgressiveMesh::build(&built.mesh, &options.pm, &|x: f64| progress.update(0.5 * x))?;
        let source = built.source;
        drop(built.mesh);
        let pyramid = Pyramid::analyze(&pm, relaxation, &|x: f64| progress.update(0.5 + 0.5 * x))?;
        Ok(ScanPyramid {
            input,
            source,
            pm,
            pyramid,
        })
    }

    /// Maps a signal in PM order onto the input's vertices (split copies averaged, vertices
    /// outside the hierarchy keep their input positions).
    pub fn to_input_positions(&self, pm_signal: &[DVec3]) -> Vec<DVec3> {
        // The PM covers every vertex of the repaired mesh (`pm_to_mesh` is a permutation of its
        // slots), and its original positions are the mesh's; entries `pm_signal` lacks keep them.
        let original = self.pm.original_positions();
        let mut mesh_values = vec![DVec3::ZERO; self.source.vertex_source.len()];
        for (i, &slot) in self.pm.pm_to_mesh().iter().enumerate() {
            if let Some(m) = mesh_values.get_mut(slot as usize) {
                *m = pm_signal.get(i).copied().unwrap_or(original[i]);
            }
        }
        self.source
            .to_input_positions(&mesh_values, &self.input.positions)
    }

    /// The input mesh with its positions replaced by `pm_signal` (PM order).
    pub fn output_mesh(&self, pm_signal: &[DVec3]) -> PolygonMesh {
        let mut out = self.input.clone();
        out.positions = self.to_input_positions(pm_signal);
        out
    }

    /// The input's positions and triangles (the repaired mesh) for previews and metrics.
    pub fn triangles(&self, pm_signal: &[DVec3]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let n = pm_signal.len().min(self.pm.original_positions().len());
        (pm_signal[..n].to_vec(), self.pm.finest_faces().to_vec())
    }
}
