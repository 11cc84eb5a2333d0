//! Rebuilding a [`ProgressiveMesh`] from decoded parts (a `.pyr` file), validating everything:
//! a damaged file must give an error here, never a panic or a debug assertion later in the
//! cursor, the analysis or the synthesis.

use super::{Pins, PmError, ProgressiveMesh, VertexSplit};
use crate::mesh::{Mesh, SlotIndex, VertexId};
#[cfg(test)]
use crate::pm::collapse::vertex_split;
use crate::pm::{FlatReplay, canonical_sorted};
use glam::DVec3;

/// The stored parts of a progressive mesh; everything else is derived.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PmParts {
    /// Number of base vertices `n0`.
    pub n_base: usize,
    /// Original positions in PM order, including the vertices without faces at the end.
    pub positions: Vec<DVec3>,
    /// PM index → vertex slot of the input mesh: a permutation of `0..positions.len()`.
    pub pm_to_mesh: Vec<u32>,
    /// The vertex splits, split `i` creating PM vertex `n_base + i`.
    pub splits: Vec<VertexSplit>,
    /// Finest-level triangles in PM indices, in the input mesh's face order.
    pub faces: Vec<[u32; 3]>,
    /// Quadric error of each split's collapse.
    pub errors: Vec<f32>,
    /// Per pass of a hierarchy built in blocks, its run of splits and the vertices pinned in it
    /// ([`ProgressiveMesh::pins`]): its detail pyramid leaves them untouched in their pass.
    /// `None` for a hierarchy built in one piece.
    pub pins: Option<Pins>,
}

fn invalid(reason: impl Into<String>) -> PmError {
    PmError::Internal(format!(
        "inconsistent progressive mesh data: {}",
        reason.into()
    ))
}

/// Rotates a triangle so that its smallest index comes first (orientation kept).
#[cfg(test)]
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

/// The base mesh on PM vertices `0..n_base` and the split records, replayed from the base:
/// the mesh after the first `k` splits, each checked to apply exactly (vertex slot == PM index).
pub struct SplitReplay {
    mesh: Mesh,
    handles: Vec<VertexId>,
}

impl SplitReplay {
    /// Builds the base mesh from its triangles; every base vertex must be used by a face, and
    /// the triangles must form a clean manifold (no repair by the mesh builder).
    pub fn new(base_positions: &[DVec3], base_faces: &[[u32; 3]]) -> Result<Self, PmError> {
        if base_positions.iter().any(|p| !p.is_finite()) {
            return Err(invalid("non-finite base position"));
        }
        let n = base_positions.len() as u64;
        if base_faces
            .iter()
            .any(|t| t.iter().any(|&x| u64::from(x) >= n))
        {
            return Err(invalid("base face refers to a vertex past the base"));
        }
        let built = Mesh::from_triangles(base_positions, base_faces)
            .map_err(|e| invalid(format!("base mesh: {e}")))?;
        if built.report.repaired_anything() || built.mesh.n_vertices() != base_positions.len() {
            return Err(invalid("base mesh is not a clean manifold triangle mesh"));
        }
        let handles: Vec<VertexId> = built.mesh.vertices().collect();
        if handles.iter().enumerate().any(|(i, v)| v.slot() != i) {
            return Err(invalid("base mesh vertex slots are not dense"));
        }
        if handles.iter().any(|&v| built.mesh.is_isolated(v)) {
            return Err(invalid("base vertex without a face"));
        }
        Ok(SplitReplay {
            mesh: built.mesh,
            handles,
        })
    }

    /// The current mesh (vertex slot == PM index).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Number of vertices so far.
    pub fn level(&self) -> usize {
        self.handles.len()
    }

    /// Handle of PM vertex `i`, if it exists yet.
    pub fn vertex(&self, i: u32) -> Option<VertexId> {
        self.handles.get(i as usize).copied()
    }

    /// The PM indices around `v` counter-clockwise (boundary vertices start at their boundary
    /// out-edge) — the ring the `.pyr` format indexes wings into.
    pub fn ring(&self, v: u32, out: &mut Vec<u32>) -> Result<(), PmError> {
        out.clear();
        let h = self
            .vertex(v)
            .ok_or_else(|| invalid(format!("survivor {v} does not exist yet")))?;
        out.extend(
            self.mesh
                .outgoing(h)
                .map(|e| self.mesh.to_vertex(e).slot() as u32),
        );
        Ok(())
    }

    /// Applies the next split (which must create vertex `level()`).
    #[cfg(test)]
    pub(crate) fn apply(&mut self, s: &VertexSplit, position: DVec3) -> Result<(), PmError> {
        let level = self.level();
        if s.vertex as usize != level {
            return Err(invalid(format!(
                "split creates vertex {}, expected {level}",
                s.vertex
            )));
        }
        if !position.is_finite() {
            return Err(invalid(format!("vertex {level} has a non-finite position")));
        }
        let get = |x: u32| {
            self.vertex(x)
                .ok_or_else(|| invalid(format!("split {level} refers to future vertex {x}")))
        };
        let v = get(s.survivor)?;
        let l = s.left.map(get).transpose()?;
        let r = s.right.map(get).transpose()?;
        let u = vertex_split(&mut self.mesh, v, l, r, position)
            .map_err(|e| invalid(format!("split creating vertex {level}: {e}")))?;
        if u.slot() != level {
            return Err(invalid("vertex split did not create the next vertex slot"));
        }
        self.handles.push(u);
        Ok(())
    }

    /// The current triangles in PM indices, canonically rotated and sorted.
    #[cfg(test)]
    pub(crate) fn canonical_faces(&self) -> Vec<[u32; 3]> {
        let mut f: Vec<[u32; 3]> = self
            .mesh
            .faces()
            .map(|f| canonical(self.mesh.face_vertices(f).map(|v| v.slot() as u32)))
            .collect();
        f.sort_unstable();
        f
    }
}

impl ProgressiveMesh {
    /// The triangles of the base level in finest-face order (what [`Self::base_mesh`] builds).
    pub(crate) fn base_triangles(&self) -> Vec<[u32; 3]> {
        self.level_triangles(self.n_base_vertices())
    }

    /// Rebuilds a progressive mesh from stored parts, checking every invariant the cursor,
    /// the analysis and the synthesis rely on: the permutation, index ranges, that every split
    /// applies exactly to the base mesh, and that all splits together give exactly `faces`.
    /// Cost: one replay of all splits ([`FlatReplay`]).
    pub fn from_parts(parts: PmParts) -> Result<ProgressiveMesh, PmError> {
        let mut pm = Self::unreplayed(parts, None)?;
        let n_base = pm.n_base;
        let base = pm.base_triangles();
        let mut replay = FlatReplay::new(&pm.positions[..n_base], &base, pm.splits.len())?;
        for s in &pm.splits {
            replay.apply(s)?;
        }
        pm.n_base_faces = replay.n_base_faces();
        if canonical_sorted(&pm.faces, n_base + pm.splits.len()) != replay.canonical_faces() {
            return Err(invalid("the splits do not rebuild the finest faces"));
        }
        Ok(pm)
    }

    /// [`Self::from_parts`] for a decoder that has already replayed `parts.splits` on a
    /// [`FlatReplay`] of the base mesh (which gave `n_base_faces` base faces) and checked that
    /// `parts.faces` are exactly the faces the replay rebuilt: everything else is checked as
    /// in `from_parts`, without replaying or comparing the faces a second time. `mesh_to_pm`,
    /// when given, is the inverse of `parts.pm_to_mesh`, which the caller has checked to be a
    /// permutation (else it is computed and checked here).
    pub(crate) fn from_checked_parts(
        parts: PmParts,
        n_base_faces: usize,
        mesh_to_pm: Option<Vec<u32>>,
    ) -> Result<ProgressiveMesh, PmError> {
        let mut pm = Self::unreplayed(parts, mesh_to_pm)?;
        pm.n_base_faces = n_base_faces;
        Ok(pm)
    }

    /// A copy of the parts this hierarchy is made of (what a `.pyr` file stores of it):
    /// [`Self::from_parts`] rebuilds the same hierarchy from them.
    pub fn to_parts(&self) -> PmParts {
        PmParts {
            n_base: self.n_base_vertices(),
            positions: self.original_positions().to_vec(),
            pm_to_mesh: self.pm_to_mesh().to_vec(),
            splits: self.splits().to_vec(),
            faces: self.finest_faces().to_vec(),
            errors: self.split_errors().to_vec(),
            pins: self.pins().cloned(),
        }
    }

    /// The parts with every check that needs no replay (`inverse`: see
    /// [`Self::from_checked_parts`]).
    fn unreplayed(parts: PmParts, inverse: Option<Vec<u32>>) -> Result<ProgressiveMesh, PmError> {
        let PmParts {
            n_base,
            positions,
            pm_to_mesh,
            splits,
            faces,
            errors,
            pins,
        } = parts;
        let total = positions.len();
        let n_fin = n_base
            .checked_add(splits.len())
            .filter(|&n| n <= total)
            .ok_or_else(|| invalid("more levels than vertices"))?;
        if pm_to_mesh.len() != total || errors.len() != splits.len() {
            return Err(invalid("array lengths disagree"));
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(invalid("non-finite position"));
        }
        let mesh_to_pm = match inverse.filter(|m| m.len() == total) {
            Some(m) => m,
            None => {
                let mut mesh_to_pm = vec![super::NONE; total];
                for (i, &s) in pm_to_mesh.iter().enumerate() {
                    match mesh_to_pm.get_mut(s as usize) {
                        Some(m) if *m == super::NONE => *m = i as u32,
                        _ => return Err(invalid("vertex order is not a permutation")),
                    }
                }
                mesh_to_pm
            }
        };
        for (i, s) in splits.iter().enumerate() {
            let v = (n_base + i) as u32;
            let ok = s.vertex == v
                && s.survivor < v
                && s.left.is_none_or(|x| x < v)
                && s.right.is_none_or(|x| x < v);
            if !ok {
                return Err(invalid(format!("split {i} has out-of-range vertices")));
            }
        }
        if faces.iter().any(|t| {
            t.iter().any(|&x| x as usize >= n_fin) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2]
        }) {
            return Err(invalid("finest face out of range or degenerate"));
        }
        let mut pm = ProgressiveMesh {
            n_base,
            positions,
            pm_to_mesh,
            mesh_to_pm,
            splits,
            faces,
            n_base_faces: 0,
            errors,
            stop: None,
            keeps_seams: false,
            pins: None,
            first_pieces: None,
        };
        pm.set_pins(pins).map_err(|e| invalid(e.to_string()))?;
        Ok(pm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pm::PmOptions;
    use crate::progress::NoProgress;

    fn grid(n: usize) -> Mesh {
        let (p, t) = crate::mesh::shapes::grid(n, |i, j| {
            DVec3::new(i as f64, j as f64, ((i * j) % 3) as f64 * 0.1)
        });
        Mesh::from_triangles(&p, &t).unwrap().mesh
    }

    #[test]
    fn parts_round_trip() {
        let pm = ProgressiveMesh::build(&grid(6), &PmOptions::default(), &NoProgress).unwrap();
        let back = ProgressiveMesh::from_parts(pm.to_parts()).unwrap();
        assert_eq!(back.to_parts(), pm.to_parts());
        assert_eq!(back.n_base_faces(), pm.n_base_faces());
        assert_eq!(back.mesh_to_pm(), pm.mesh_to_pm());
    }

    #[test]
    fn damaged_parts_are_errors() {
        let pm = ProgressiveMesh::build(&grid(5), &PmOptions::default(), &NoProgress).unwrap();
        let good = pm.to_parts();
        let mut cases = Vec::new();
        let mut p = good.clone();
        p.splits[0].survivor = p.splits[0].vertex;
        cases.push(p);
        let mut p = good.clone();
        p.splits[3].left = Some(p.splits[3].vertex - 1);
        p.splits[3].right = p.splits[3].left;
        cases.push(p);
        let mut p = good.clone();
        p.pm_to_mesh[1] = p.pm_to_mesh[0];
        cases.push(p);
        let mut p = good.clone();
        p.faces.pop();
        cases.push(p);
        let mut p = good.clone();
        p.positions[0].x = f64::NAN;
        cases.push(p);
        let mut p = good.clone();
        p.n_base += 1;
        cases.push(p);
        let mut p = good.clone();
        p.faces[0].swap(0, 1);
        cases.push(p);
        for (i, c) in cases.into_iter().enumerate() {
            assert!(ProgressiveMesh::from_parts(c).is_err(), "case {i} accepted");
        }
    }
}
