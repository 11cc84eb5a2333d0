//! Simplification of a file-level mesh: the progressive mesh cut at a level, written with the
//! input's per-vertex attributes carried along (the behaviour of `meshpyr simplify`).

use super::progressive::{PmError, PmOptions, ProgressiveMesh};
use crate::mesh::{BuildError, Mesh, PolygonMesh};
use crate::progress::Progress;

/// When to stop simplifying.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SimplifyTarget {
    /// At most this many triangles.
    Faces(usize),
    /// At most this fraction of the input's triangles, in `(0, 1]`.
    Ratio(f64),
    /// Every collapse's quadric error (an RMS distance) at most this fraction of the bounding-box
    /// diagonal; collapses continue until the next one would exceed it.
    Error(f64),
}

/// Why a mesh could not be simplified.
#[derive(Debug, thiserror::Error)]
pub enum SimplifyError {
    /// The input cannot be turned into a half-edge mesh.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// The progressive mesh could not be built.
    #[error(transparent)]
    Pm(#[from] PmError),
    /// The target is out of range.
    #[error("invalid target: {0}")]
    InvalidTarget(String),
}

/// The simplified mesh and what happened.
#[derive(Clone, Debug)]
pub struct Simplified {
    /// The result: triangles, the surviving vertices at their original positions (PM order),
    /// the input's per-vertex attributes gathered along; per-face attributes and extra
    /// elements are dropped (their rows no longer exist).
    pub mesh: PolygonMesh,
    /// Triangles of the input after the builder's repairs.
    pub input_triangles: usize,
    /// For each output vertex, the input vertex it came from.
    pub source_rows: Vec<u32>,
}

/// Simplifies `input` by quadric-error half-edge collapses (see [`ProgressiveMesh::build`]);
/// the stopping rule in `opts` is replaced by `target`.
pub fn simplify(
    input: &PolygonMesh,
    target: SimplifyTarget,
    opts: &PmOptions,
    progress: &dyn Progress,
) -> Result<Simplified, SimplifyError> {
    let built = Mesh::from_polygons(input)?;
    let n_faces = built.mesh.n_faces();
    let mut o = PmOptions {
        target_vertices: 0,
        target_faces: 0,
        max_error: None,
        ..opts.clone()
    };
    match target {
        SimplifyTarget::Faces(f) => o.target_faces = f,
        SimplifyTarget::Ratio(r) => {
            if !(r > 0.0 && r <= 1.0) {
                return Err(SimplifyError::InvalidTarget(format!(
                    "ratio must be in (0, 1], got {r}"
                )));
            }
            o.target_faces = (r * n_faces as f64).round() as usize;
        }
        SimplifyTarget::Error(e) => {
            if !(e >= 0.0 && e.is_finite()) {
                return Err(SimplifyError::InvalidTarget(format!(
                    "error must be a finite number >= 0, got {e}"
                )));
            }
            o.max_error = Some(e);
        }
    }
    let pm = ProgressiveMesh::build(&built.mesh, &o, progress)?;
    let n0 = pm.n_base_vertices();
    let tris = pm.level_triangles(n0);
    let source_rows: Vec<u32> = pm.pm_to_mesh()[..n0]
        .iter()
        .map(|&slot| built.source.vertex_source[slot as usize])
        .collect();
    let mut mesh = PolygonMesh::from_triangles(
        source_rows
            .iter()
            .map(|&r| input.positions[r as usize])
            .collect(),
        &tris,
    );
    mesh.position_type = input.position_type;
    mesh.comments = input.comments.clone();
    mesh.vertex_attributes = input
        .vertex_attributes
        .iter()
        .map(|a| crate::mesh::Attribute {
            name: a.name.clone(),
            data: a.data.gather(&source_rows),
        })
        .collect();
    Ok(Simplified {
        mesh,
        input_triangles: n_faces,
        source_rows,
    })
}
