//! Texture seams in the decimator: wedges, the rule that keeps seams, and the values the
//! surviving corners take.
//!
//! **Wedges** (Hoppe 1996, "Progressive meshes", §3: a vertex's corners partitioned by their
//! attribute values; Hoppe 1998, "Efficient implementation of progressive meshes"). The
//! decimator works on the position-welded mesh; each corner also belongs to a wedge, the corners
//! of one vertex with equal values: texture coordinates, corner normals, any other per-corner
//! data, and the face's material (a material border is a seam too). A vertex with one wedge is
//! smooth; with two, it lies on a seam; with more, seams meet there (or charts touch) and it
//! never moves. A seam edge is an edge whose two faces see different wedges at one of its ends.
//!
//! **The rule** (the classes of meshoptimizer's `simplify`: manifold, border, seam, complex,
//! locked; Hoppe's discontinuity curves). A half-edge collapse `u → v` moves no position and
//! invents no value: every corner of `u` takes the value `v` has in the same wedge, where "the
//! same wedge" is read off the faces that die, whose corners at `u` and `v` lie in one chart.
//! So the collapse is allowed only when that reading is a one-to-one map from `u`'s wedges:
//! - `u` with one wedge: the two dying faces must see the same wedge at `v` (otherwise `u` is the
//!   tip of a cut ending at `v`'s seam, and its faces would be torn between two charts);
//! - `u` with two wedges: `u → v` must run along the seam (the dying faces see different wedges
//!   at `u` and at `v`) and `u` must have exactly two seam edges (one seam passes through it);
//! - more wedges: never.
//!
//! Then every output corner holds a value its vertex had, on the side of the seam its face is on,
//! and a face's corners keep coming from one chart: no texture is stretched across a seam.
//!
//! **Cost.** Each wedge carries an [`AttributeQuadric`] of its faces' texture fields; the cost of
//! a collapse adds, for each wedge of `u` and the wedge of `v` it maps to, the merged quadric at
//! `v`'s position and value, normalised by their area and scaled by `(uv_weight · extent)²` so
//! that a texture-coordinate error of `1 / uv_weight` weighs as much as a distance of the bounding
//! box's largest side (meshoptimizer's `simplifyWithAttributes` weighs attributes against
//! positions in the same units).

use super::attribute_quadric::AttributeQuadric;
use super::decimate::FlatMesh;
use crate::mesh::PolygonMesh;
use crate::mesh::build::next_c;
use crate::mesh::corners::{MATERIAL_ATTRIBUTE, TEXCOORD};
use glam::{DVec2, DVec3};
use std::collections::HashMap;

const NONE: u32 = u32::MAX;

/// The wedges of a decimation's corners, their texture coordinates and attribute quadrics.
#[derive(Clone, Debug)]
pub(crate) struct Seams {
    /// The wedge of every corner `3t + k` of the corner table.
    wedge: Vec<u32>,
    /// Per wedge: the input polygon corner (an index into `face_indices`) it takes its values
    /// from.
    source_corner: Vec<u32>,
    /// Per wedge: its texture coordinates (empty without texture coordinates or weight).
    uv: Vec<DVec2>,
    /// Per wedge: the quadric of its faces' texture fields (empty like `uv`).
    quadric: Vec<AttributeQuadric>,
    /// `(uv_weight · extent)²`.
    scale: f64,
}

/// The corners a collapse pairs up, as `(wedge at u, wedge at v)` per dying face.
pub(crate) type Pairs = [Option<(u32, u32)>; 2];

impl Seams {
    /// The wedges of `input` on the builder's triangles (`corner_vertex`, each triangle from
    /// input polygon `face_source[t]`, each mesh vertex at input vertex `vertex_source[v]`), or
    /// `None` when the input has no per-corner data and at most one material: then the decimator
    /// runs exactly as without seams. `mesh` is the working mesh, whose positions the quadrics
    /// use; `uv_weight` weighs texture error against the largest side `extent`.
    pub(crate) fn of(
        input: &PolygonMesh,
        corner_vertex: &[u32],
        face_source: &[u32],
        vertex_source: &[u32],
        mesh: &FlatMesh,
        uv_weight: f64,
        extent: f64,
    ) -> Option<Seams> {
        if !is_textured(input) {
            return None;
        }
        let source_corner = source_corners(input, corner_vertex, face_source, vertex_source);
        let (wedge, representative) = wedges(input, corner_vertex, face_source, &source_corner);
        let mut seams = Seams {
            wedge,
            source_corner: representative,
            uv: Vec::new(),
            quadric: Vec::new(),
            scale: (uv_weight * extent).powi(2),
        };
        if uv_weight > 0.0 {
            seams.add_quadrics(input, corner_vertex, mesh);
        }
        Some(seams)
    }

    /// Texture coordinates and attribute quadrics per wedge, when the input has texture
    /// coordinates.
    fn add_quadrics(&mut self, input: &PolygonMesh, corner_vertex: &[u32], mesh: &FlatMesh) {
        let Some(tc) = input.corner_attribute(TEXCOORD) else {
            return;
        };
        if tc.columns.len() < 2 {
            return;
        }
        let n = self.source_corner.len();
        let mut uv = vec![DVec2::ZERO; n];
        let mut valued = vec![false; n];
        for (w, &pc) in self.source_corner.iter().enumerate() {
            if let Some(r) = tc.row(pc as usize) {
                uv[w] = DVec2::new(tc.columns[0].data.get_f64(r), tc.columns[1].data.get_f64(r));
                valued[w] = uv[w].is_finite();
            }
        }
        let mut quadric = vec![AttributeQuadric::default(); n];
        for (t, tri) in corner_vertex.chunks_exact(3).enumerate() {
            let w = [0, 1, 2].map(|k| self.wedge[3 * t + k] as usize);
            if !w.iter().all(|&w| valued[w]) {
                continue;
            }
            let p = [0, 1, 2].map(|k| mesh.position(tri[k]));
            if let Some(q) = AttributeQuadric::of_triangle(p, w.map(|w| uv[w])) {
                for w in w {
                    quadric[w].add(&q);
                }
            }
        }
        self.uv = uv;
        self.quadric = quadric;
    }

    /// The seams of one block of a partitioned build (`partition/block.rs`): the wedge of
    /// every corner of its triangles in the block's numbering, and per wedge its texture
    /// coordinates and attribute quadric (both empty without texture coordinates or weight).
    /// Decimating needs nothing else, so the wedges carry no input corner.
    pub(crate) fn of_block(
        wedge: Vec<u32>,
        uv: Vec<DVec2>,
        quadric: Vec<AttributeQuadric>,
        scale: f64,
    ) -> Seams {
        Seams {
            wedge,
            source_corner: Vec::new(),
            uv,
            quadric,
            scale,
        }
    }

    /// The wedges of the corners of `mesh`'s live triangles, in the order of
    /// [`FlatMesh::triangles`].
    pub(crate) fn live_wedges(&self, mesh: &FlatMesh) -> Vec<[u32; 3]> {
        super::decimate::live_triangles(mesh)
            .into_iter()
            .map(|t| [0, 1, 2].map(|k| self.wedge[3 * t as usize + k]))
            .collect()
    }

    /// Per wedge: texture coordinates and attribute quadric (both empty without texture
    /// coordinates or weight), and the weight's scale `(uv_weight · extent)²`.
    pub(crate) fn wedge_tables(self) -> (Vec<DVec2>, Vec<AttributeQuadric>, f64) {
        (self.uv, self.quadric, self.scale)
    }

    /// The attribute quadric of wedge `w`, `None` without texture coordinates or weight.
    pub(crate) fn quadric(&self, w: u32) -> Option<&AttributeQuadric> {
        self.quadric.get(w as usize)
    }

    /// The wedge of corner `c` of the corner table.
    pub(crate) fn wedge(&self, c: u32) -> u32 {
        self.wedge[c as usize]
    }

    /// The input polygon corner whose values wedge `w` carries.
    pub(crate) fn source_corner(&self, w: u32) -> u32 {
        self.source_corner[w as usize]
    }

    /// The wedges the faces dying in the collapse of `h = u → v` see at `u` and at `v`.
    fn pairs(&self, mesh: &FlatMesh, h: u32) -> Pairs {
        let o = mesh.twin(h);
        let left = (!mesh.is_boundary_halfedge(h))
            .then(|| (self.wedge[h as usize], self.wedge[next_c(h) as usize]));
        let right = (!mesh.is_boundary_halfedge(o))
            .then(|| (self.wedge[next_c(o) as usize], self.wedge[o as usize]));
        [left, right]
    }

    /// Whether collapsing `h = u → v` keeps the seams (the rule in the module docs).
    pub(super) fn allows(&self, mesh: &FlatMesh, h: u32) -> bool {
        let u = mesh.tail_vertex(h);
        let mut wedges: smallvec::SmallVec<[u32; 4]> = smallvec::SmallVec::new();
        let mut seam_edges = 0;
        mesh.for_each_corner(u, |c| {
            let w = self.wedge[c as usize];
            if !wedges.contains(&w) {
                wedges.push(w);
            }
            // Each interior edge at u leaves u in exactly one of u's corners.
            let t = mesh.twin(c);
            if !mesh.is_boundary_halfedge(t) && self.wedge[next_c(t) as usize] != w {
                seam_edges += 1;
            }
        });
        seam_rule(wedges.len(), seam_edges, self.pairs(mesh, h))
    }

    /// The attribute part of the cost of collapsing `h = u → v`, `v` at `pv` (0 without texture
    /// coordinates): the merged wedge quadrics at the values `u`'s wedges would take,
    /// normalised by their area, in length² (see the module docs).
    pub(super) fn cost(&self, mesh: &FlatMesh, h: u32, pv: DVec3) -> f64 {
        if self.quadric.is_empty() {
            return 0.0;
        }
        let [l, r] = self.pairs(mesh, h);
        let mut raw = 0.0;
        let mut weight = 0.0;
        for (k, pair) in [l, r].into_iter().enumerate() {
            let Some((wu, wv)) = pair else { continue };
            if k == 1 && l.is_some_and(|l| l.0 == wu) {
                continue; // one wedge of u, already counted
            }
            let (qu, qv) = (&self.quadric[wu as usize], &self.quadric[wv as usize]);
            let a = self.uv[wv as usize];
            raw += qu.raw(pv, a) + qv.raw(pv, a);
            weight += qu.weight + qv.weight;
        }
        if weight > 0.0 {
            self.scale * raw / weight
        } else {
            0.0
        }
    }

    /// Before the (allowed) collapse of `h = u → v`: gives every corner of `u` the wedge of `v`
    /// it maps to and merges the wedges' quadrics.
    pub(super) fn collapse(&mut self, mesh: &FlatMesh, h: u32) {
        let pairs = self.pairs(mesh, h);
        let map = |w: u32| pairs.iter().flatten().find(|p| p.0 == w).map_or(w, |p| p.1);
        let mut at_u: smallvec::SmallVec<[u32; 16]> = smallvec::SmallVec::new();
        mesh.for_each_corner(mesh.tail_vertex(h), |c| at_u.push(c));
        for c in at_u {
            let w = &mut self.wedge[c as usize];
            *w = map(*w);
        }
        if self.quadric.is_empty() {
            return;
        }
        let mut merged = [NONE; 2];
        for (k, (wu, wv)) in pairs.into_iter().flatten().enumerate() {
            if wu != wv && !merged.contains(&wu) {
                let q = self.quadric[wu as usize];
                self.quadric[wv as usize].add(&q);
                merged[k] = wu;
            }
        }
    }
}

/// The seam rule (module docs) for a collapse `u → v`: `u` has `wedges` wedges and
/// `seam_edges` interior edges whose two faces see different wedges at `u`; `pairs` holds the
/// `(wedge at u, wedge at v)` of the face on the left of `u → v` and of the one on the right.
pub(crate) fn seam_rule(wedges: usize, seam_edges: usize, pairs: Pairs) -> bool {
    match (wedges, pairs) {
        (1, [Some(l), Some(r)]) => l.1 == r.1,
        (1, _) => true,
        (2, [Some(l), Some(r)]) => l.0 != r.0 && l.1 != r.1 && seam_edges == 2,
        _ => false,
    }
}

/// Whether `input` has per-corner data or more than one material: then the decimator keeps
/// its seams.
pub(crate) fn is_textured(input: &PolygonMesh) -> bool {
    !input.corner_attributes.is_empty() || materials_differ(input)
}

fn materials_differ(input: &PolygonMesh) -> bool {
    input.face_attribute(MATERIAL_ATTRIBUTE).is_some_and(|m| {
        let first = (!m.data.is_empty()).then(|| m.data.get_f64(0).to_bits());
        (0..m.data.len()).any(|f| Some(m.data.get_f64(f).to_bits()) != first)
    })
}

/// The wedge of every corner of the builder's triangles (`corner_vertex`, triangle `t` from
/// input polygon `face_source[t]`, corner `c` from input polygon corner `source_corner[c]`),
/// numbered in order of first corner, and per wedge the first such input corner: corners of
/// one vertex share a wedge when their per-corner values and their faces' materials are equal.
pub(crate) fn wedges(
    input: &PolygonMesh,
    corner_vertex: &[u32],
    face_source: &[u32],
    source_corner: &[u32],
) -> (Vec<u32>, Vec<u32>) {
    let material = input
        .face_attribute(MATERIAL_ATTRIBUTE)
        .filter(|_| materials_differ(input));
    let mut ids: HashMap<Vec<u64>, u32> = HashMap::new();
    let mut wedge = Vec::with_capacity(corner_vertex.len());
    let mut representative = Vec::new();
    let mut key = Vec::new();
    for (c, (&v, &pc)) in corner_vertex.iter().zip(source_corner).enumerate() {
        key.clear();
        key.push(v as u64);
        if let Some(m) = material {
            key.push(m.data.get_f64(face_source[c / 3] as usize).to_bits());
        }
        for a in &input.corner_attributes {
            match a.row(pc as usize) {
                None => key.push(u64::MAX),
                Some(r) => key.extend(a.columns.iter().map(|col| col.data.get_f64(r).to_bits())),
            }
        }
        let next = representative.len() as u32;
        let id = *ids.entry(key.clone()).or_insert(next);
        if id == next {
            representative.push(pc);
        }
        wedge.push(id);
    }
    (wedge, representative)
}

/// For every corner of the builder's triangles, the input polygon corner it came from: the
/// corner of polygon `face_source[t]` at the same input vertex (the builder fans polygons from
/// their first corner and may flip a triangle, so the position in the triangle says nothing).
pub(crate) fn source_corners(
    input: &PolygonMesh,
    corner_vertex: &[u32],
    face_source: &[u32],
    vertex_source: &[u32],
) -> Vec<u32> {
    corner_vertex
        .iter()
        .enumerate()
        .map(|(c, &v)| {
            let f = face_source[c / 3] as usize;
            let (s, e) = (input.face_starts[f], input.face_starts[f + 1]);
            let iv = vertex_source[v as usize];
            (s..e)
                .find(|&k| input.face_indices[k as usize] == iv)
                .unwrap_or(s)
        })
        .collect()
}
