//! The corner table: the builder's repaired triangles before any half-edge record exists,
//! with the corner arithmetic every reader of it shares.

use super::repair::repair_triangles;
use super::{BuildError, BuildReport, NONE, SourceMap};
use crate::mesh::polygon::PolygonMesh;

/// The builder's result before any half-edge record exists: the repaired triangles as a corner
/// table. Corner `c = 3t + k` is corner `k` of triangle `t` (the input's triangle order, each
/// oriented consistently); half-edge `c` runs from corner `c` to the next corner of its
/// triangle. [`Mesh::from_polygons`] turns it into records one to one: half-edge slot `c` is
/// half-edge `c`, face slot `t` is triangle `t`, vertex slot `i` is vertex `i`, and the boundary
/// half-edges follow in the order of their interior twins. Flat consumers (the decimator behind
/// `meshpyr simplify`) use it directly and skip the records.
#[derive(Clone, Debug)]
pub(crate) struct CornerTable {
    /// Mesh vertex of every corner.
    pub corner_vertex: Vec<u32>,
    /// The twin half-edge of every half-edge, `u32::MAX` on a boundary.
    pub mate: Vec<u32>,
}

/// A [`CornerTable`] with the repair report and the map back onto the input.
#[derive(Clone, Debug)]
pub(crate) struct Repaired {
    /// The repaired triangles.
    pub corners: CornerTable,
    /// What the builder changed.
    pub report: BuildReport,
    /// Mesh → input correspondence (mesh vertex `i` sits at input vertex `vertex_source[i]`).
    pub source: SourceMap,
}

impl CornerTable {
    /// Runs the builder's repairs (see the module docs) without making half-edge records.
    /// Fails like [`Mesh::from_polygons`].
    pub(crate) fn from_polygons(input: &PolygonMesh) -> Result<Repaired, BuildError> {
        let mut report = BuildReport::default();
        let nv = input.positions.len();
        if let Some(vertex) = input.positions.iter().position(|p| !p.is_finite()) {
            return Err(BuildError::NonFinite { vertex });
        }
        if nv >= NONE as usize {
            return Err(BuildError::TooLarge);
        }
        let mut tris: Vec<[u32; 3]> = Vec::with_capacity(input.n_triangles());
        let mut tri_source: Vec<u32> = Vec::with_capacity(input.n_triangles());
        for (fi, poly) in input.faces().enumerate() {
            if poly.len() > 3 {
                report.triangulated_polygons += 1;
            }
            if let Some(&index) = poly.iter().find(|&&i| i as usize >= nv) {
                return Err(BuildError::IndexOutOfRange {
                    face: fi,
                    index,
                    vertices: nv,
                });
            }
            for k in 1..poly.len().saturating_sub(1) {
                let t = [poly[0], poly[k], poly[k + 1]];
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                    report.dropped_repeated_index += 1;
                } else {
                    tris.push(t);
                    tri_source.push(fi as u32);
                }
            }
        }
        if tris.len() >= (NONE / 3) as usize {
            return Err(BuildError::TooLarge);
        }
        let (corners, vertex_source) = repair_triangles(&input.positions, &tris, &mut report);
        Ok(Repaired {
            corners,
            report,
            source: SourceMap {
                vertex_source,
                face_source: tri_source,
                input_vertices: nv,
            },
        })
    }

    /// Number of triangles.
    pub(crate) fn n_triangles(&self) -> usize {
        self.corner_vertex.len() / 3
    }
}

/// Half-edge `c = 3t + k` runs from corner `k` of triangle `t` to corner `k + 1`: the next
/// corner of its triangle (the corner-table arithmetic, shared with `pm::decimate`).
#[inline]
pub(crate) fn next_c(c: u32) -> u32 {
    if c % 3 == 2 { c - 2 } else { c + 1 }
}

/// The previous corner of `c`'s triangle.
#[inline]
pub(crate) fn prev_c(c: u32) -> u32 {
    if c.is_multiple_of(3) { c + 2 } else { c - 1 }
}
