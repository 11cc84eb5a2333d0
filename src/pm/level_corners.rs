//! The corners of every level of a progressive mesh that keeps texture seams, derived from the
//! finest corners and the collapse records alone (no per-level data is stored).
//!
//! A level's triangles are finest triangles with vertices renamed (a half-edge collapse `u → v`
//! moves no vertex and invents no value), and each of their corners takes the value of the
//! survivor's corner in the same wedge (`docs/seams.md`, "What is kept"). Which wedge that is
//! depends on the order of the collapses, so it is found by replaying them:
//!
//! 1. number the finest corners' wedges exactly as the build did (`super::seams::wedges`: the
//!    corners of one vertex with equal per-corner values and material), each wedge carrying the
//!    input polygon corner it takes its values from;
//! 2. undo the splits from the last to the one that creates level `n`'s last vertex: for the
//!    collapse `u → v`, the two faces holding both die and tell which wedge of `v` each wedge of
//!    `u` becomes (the face on the left of `u → v` first, as the build's `Seams::collapse`);
//!    every other face at `u` renames `u` to `v` and its corner there takes the mapped wedge;
//! 3. check each collapse against the seam rule on the way (`super::seams::seam_rule`): a record
//!    that breaks it (a damaged file, or a hierarchy built without the rule) is an error rather
//!    than a face textured across a seam.
//!
//! The surviving faces, in finest order, are [`ProgressiveMesh::level_triangles`]; the replay
//! touches each face once per collapse of one of its vertices, so a level costs about one pass
//! over the finest corners per level of vertex valence. The same records give the same corners
//! in memory after a build and after reading a `.pyr` file.

use super::ProgressiveMesh;
use super::seams::{Pairs, is_textured, seam_rule, source_corners, wedges};
use crate::mesh::{PolygonMesh, SourceMap};

/// Level `n`'s triangles as the finest faces that survive it, and where each corner's values
/// come from.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelFaces {
    /// The triangles in PM indices `0..n`, in the order of the finest faces (the triangles of
    /// [`ProgressiveMesh::level_triangles`]).
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, the finest face it is (an index into
    /// [`ProgressiveMesh::finest_faces`], i.e. a triangle of the mesh builder's table).
    pub faces: Vec<u32>,
    /// For each corner `3i + k` of the triangles, the corner of the input polygons (an index
    /// into [`PolygonMesh::face_indices`]) whose per-corner values it takes.
    pub corners: Vec<u32>,
}

/// A collapse record that breaks a texture seam: the hierarchy does not keep the seams below
/// the level it creates.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the collapse that removes vertex {vertex} (level {level}) breaks a texture seam")]
pub struct SeamBreak {
    /// The PM vertex the collapse removes.
    pub vertex: u32,
    /// The level whose last vertex it is (levels below it lose the seam).
    pub level: usize,
}

/// The triangles of level `n` (clamped to the valid range) of `pm`, the hierarchy of `input`
/// whose repaired mesh maps back through `source`, with the input corner each of their corners
/// takes its values from (see the module docs).
pub fn level_corners(
    pm: &ProgressiveMesh,
    input: &PolygonMesh,
    source: &SourceMap,
    n: usize,
) -> Result<LevelFaces, SeamBreak> {
    let n = n.clamp(pm.n_base_vertices(), pm.n_vertices());
    let mut faces: Vec<[u32; 3]> = pm.finest_faces().to_vec();
    // The builder's vertex of every finest corner: what the build numbered its wedges by.
    let slot_of: Vec<u32> = faces
        .iter()
        .flat_map(|t| t.map(|x| pm.pm_to_mesh()[x as usize]))
        .collect();
    let polygon_corner =
        source_corners(input, &slot_of, &source.face_source, &source.vertex_source);
    let (mut wedge, representative) = wedges(input, &slot_of, &source.face_source, &polygon_corner);
    drop((slot_of, polygon_corner));
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); pm.n_vertices()];
    for (f, t) in faces.iter().enumerate() {
        for &x in t {
            around[x as usize].push(f as u32);
        }
    }
    let mut dead = vec![false; faces.len()];
    let n_base = pm.n_base_vertices();
    for (i, s) in pm.splits().iter().enumerate().skip(n - n_base).rev() {
        let level = n_base + i + 1;
        let at_u = std::mem::take(&mut around[s.vertex as usize]);
        let live: Vec<u32> = at_u.into_iter().filter(|&f| !dead[f as usize]).collect();
        let collapse = Collapse {
            u: s.vertex,
            v: s.survivor,
            faces: &faces,
            wedge: &wedge,
            live: &live,
        };
        let (pairs, dying) = collapse.pairs();
        if !seam_rule(collapse.n_wedges(), collapse.seam_edges(), pairs) {
            return Err(SeamBreak {
                vertex: s.vertex,
                level,
            });
        }
        let map = |w: u32| pairs.iter().flatten().find(|p| p.0 == w).map_or(w, |p| p.1);
        for f in live {
            if dying.contains(&Some(f)) {
                dead[f as usize] = true;
                continue;
            }
            let k = corner_of(&faces[f as usize], s.vertex);
            let c = 3 * f as usize + k;
            wedge[c] = map(wedge[c]);
            faces[f as usize][k] = s.survivor;
            around[s.survivor as usize].push(f);
        }
    }
    let mut level = LevelFaces {
        triangles: Vec::new(),
        faces: Vec::new(),
        corners: Vec::new(),
    };
    for (f, t) in faces.iter().enumerate() {
        if !dead[f] {
            level.triangles.push(*t);
            level.faces.push(f as u32);
            level
                .corners
                .extend((0..3).map(|k| representative[wedge[3 * f + k] as usize]));
        }
    }
    Ok(level)
}

/// The position (0, 1 or 2) of vertex `x` in triangle `t` (0 if absent, which a face listed
/// around `x` never is).
fn corner_of(t: &[u32; 3], x: u32) -> usize {
    t.iter().position(|&y| y == x).unwrap_or(0)
}

/// The faces at `u` just before the collapse `u → v`, with their corners' wedges.
struct Collapse<'a> {
    u: u32,
    v: u32,
    faces: &'a [[u32; 3]],
    wedge: &'a [u32],
    /// The live faces holding `u`.
    live: &'a [u32],
}

impl Collapse<'_> {
    /// The wedge at vertex `x` of face `f`.
    fn wedge_at(&self, f: u32, x: u32) -> u32 {
        self.wedge[3 * f as usize + corner_of(&self.faces[f as usize], x)]
    }

    /// The vertex after `x` in face `f` (counter-clockwise).
    fn after(&self, f: u32, x: u32) -> u32 {
        self.faces[f as usize][(corner_of(&self.faces[f as usize], x) + 1) % 3]
    }

    /// `(wedge at u, wedge at v)` of the dying face on the left of `u → v` and of the one on
    /// its right, and those faces.
    fn pairs(&self) -> (Pairs, [Option<u32>; 2]) {
        let mut pairs: Pairs = [None, None];
        let mut dying = [None, None];
        for &f in self.live {
            if !self.faces[f as usize].contains(&self.v) {
                continue;
            }
            let side = if self.after(f, self.u) == self.v {
                0
            } else {
                1
            };
            pairs[side] = Some((self.wedge_at(f, self.u), self.wedge_at(f, self.v)));
            dying[side] = Some(f);
        }
        (pairs, dying)
    }

    /// Distinct wedges at `u`.
    fn n_wedges(&self) -> usize {
        let mut seen: smallvec::SmallVec<[u32; 4]> = smallvec::SmallVec::new();
        for &f in self.live {
            let w = self.wedge_at(f, self.u);
            if !seen.contains(&w) {
                seen.push(w);
            }
        }
        seen.len()
    }

    /// Interior edges at `u` whose two faces see different wedges at `u`.
    fn seam_edges(&self) -> usize {
        let mut count = 0;
        for &f in self.live {
            let x = self.after(f, self.u);
            // The face across the edge u → x runs x → u.
            let across = self.live.iter().find(|&&g| {
                g != f && self.faces[g as usize].contains(&x) && self.after(g, x) == self.u
            });
            if let Some(&g) = across
                && self.wedge_at(g, self.u) != self.wedge_at(f, self.u)
            {
                count += 1;
            }
        }
        count
    }
}

/// Level `n` (clamped to the valid range) of `pm`, the hierarchy of `input` whose repaired
/// mesh maps back through `source`, as a mesh: PM vertices `0..n` at their input positions
/// with their per-vertex attributes, the level's triangles in finest order, each with its
/// input polygon's face attributes, material and groups, and, when the hierarchy kept the
/// seams ([`ProgressiveMesh::keeps_seams`]), its corners' per-corner data (the module docs;
/// otherwise no per-corner data). What `simplify` writes for the same cut; an error when a
/// collapse above the level broke a seam the hierarchy says it kept.
pub fn level_mesh(
    pm: &ProgressiveMesh,
    input: &PolygonMesh,
    source: &SourceMap,
    n: usize,
) -> Result<PolygonMesh, SeamBreak> {
    let n = n.clamp(pm.n_base_vertices(), pm.n_vertices());
    let (triangles, faces, corners) = if pm.keeps_seams() && is_textured(input) {
        let level = level_corners(pm, input, source, n)?;
        (level.triangles, level.faces, Some(level.corners))
    } else {
        let (triangles, faces) = surviving_faces(pm, n);
        (triangles, faces, None)
    };
    let rows: Vec<u32> = pm.pm_to_mesh()[..n]
        .iter()
        .map(|&v| source.vertex_source[v as usize])
        .collect();
    let faces: Vec<u32> = faces
        .iter()
        .map(|&f| source.face_source[f as usize])
        .collect();
    Ok(super::simplify::cut_mesh(
        input,
        &rows,
        &triangles,
        &faces,
        corners.as_deref(),
    ))
}

/// The triangles of level `n` and the finest face each one is (as
/// [`ProgressiveMesh::level_triangles`]: every vertex mapped to its ancestor at the level,
/// degenerate triangles dropped).
fn surviving_faces(pm: &ProgressiveMesh, n: usize) -> (Vec<[u32; 3]>, Vec<u32>) {
    let n_base = pm.n_base_vertices();
    let mut ancestor: Vec<u32> = (0..pm.n_vertices() as u32).collect();
    for x in n..pm.n_vertices() {
        ancestor[x] = ancestor[pm.splits()[x - n_base].survivor as usize];
    }
    let mut triangles = Vec::new();
    let mut faces = Vec::new();
    for (f, t) in pm.finest_faces().iter().enumerate() {
        let t = t.map(|x| ancestor[x as usize]);
        if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
            triangles.push(t);
            faces.push(f as u32);
        }
    }
    (triangles, faces)
}
