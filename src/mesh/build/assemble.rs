//! Half-edge assembly: the records of a repaired corner table, one to one (half-edge slot
//! `c` is corner `c`, face slot `t` triangle `t`), wired without a handle table.

use super::corners::{CornerTable, next_c, prev_c};
use super::{NONE, SourceMap};
use crate::mesh::halfedge::{
    FaceId, FaceRecord, HalfedgeId, HalfedgeRecord, Mesh, VertexId, VertexRecord,
};
use glam::DVec3;
use slotmap::SlotMap;

/// The handle a fresh slotmap gives its `i`-th insertion. Lets the builder wire `next`,
/// `prev` and `twin` before the targets exist, without a handle table; every insertion is
/// checked against it in debug builds.
#[inline]
fn fresh_key<K: slotmap::Key>(i: usize) -> K {
    // slotmap keys are (version << 32 | slot); slot 0 is the sentinel, occupied versions are odd.
    K::from(slotmap::KeyData::from_ffi((1u64 << 32) | (i as u64 + 1)))
}

/// Step 4 of the build: the half-edge records of a corner table. Handles are predicted with
/// `fresh_key`: half-edge c is insertion c, boundary half-edges follow in order of their
/// interior twins.
pub(super) fn assemble(positions: &[DVec3], corners: &CornerTable, source: &SourceMap) -> Mesh {
    let links = Links::of(corners, source.vertex_source.len());
    // The three record maps are independent: the half-edges (most of the memory, so most of
    // the page faults) fill on one thread while the vertices and faces fill on another.
    let mut mesh = Mesh::new();
    let (vertices, faces, halfedges) = (&mut mesh.vertices, &mut mesh.faces, &mut mesh.halfedges);
    rayon::join(
        || {
            insert_vertices(vertices, positions, &source.vertex_source, &links);
            insert_faces(faces, corners.corner_vertex.len() / 3);
        },
        || insert_halfedges(halfedges, corners, &links),
    );
    mesh
}

/// How the records link up beyond the corner table: the boundary half-edges and the
/// half-edge each vertex stores.
struct Links {
    /// The slot of each corner's boundary twin (`NONE` for a paired half-edge).
    boundary_index: Vec<u32>,
    n_boundary: u32,
    /// Per vertex its single boundary out-going and in-coming half-edge (unique after fan
    /// splitting), or `NONE`.
    boundary_out: Vec<u32>,
    boundary_in: Vec<u32>,
    /// Per vertex its first corner, or `NONE`.
    first_corner: Vec<u32>,
}

impl Links {
    fn of(corners: &CornerTable, n_vertices: usize) -> Links {
        let (boundary_index, n_boundary) = number_boundary_halfedges(&corners.mate);
        let (boundary_out, boundary_in) =
            boundary_ends(&corners.corner_vertex, &boundary_index, n_vertices);
        Links {
            boundary_index,
            n_boundary,
            boundary_out,
            boundary_in,
            first_corner: first_corners(&corners.corner_vertex, n_vertices),
        }
    }
}

/// The slot of the boundary twin of every unpaired half-edge (after all `mate.len()` interior
/// ones, in corner order), and how many there are.
fn number_boundary_halfedges(mate: &[u32]) -> (Vec<u32>, u32) {
    let nh = mate.len();
    let mut boundary_index = vec![NONE; nh];
    let mut n_boundary = 0u32;
    for (c, &m) in mate.iter().enumerate() {
        if m == NONE {
            boundary_index[c] = nh as u32 + n_boundary;
            n_boundary += 1;
        }
    }
    (boundary_index, n_boundary)
}

/// Per vertex its boundary out-going and in-coming half-edge. The boundary twin of c leaves
/// c's head and arrives at c's tail.
fn boundary_ends(
    corner_vertex: &[u32],
    boundary_index: &[u32],
    n_vertices: usize,
) -> (Vec<u32>, Vec<u32>) {
    let mut boundary_out = vec![NONE; n_vertices];
    let mut boundary_in = vec![NONE; n_vertices];
    for c in 0..corner_vertex.len() as u32 {
        let b = boundary_index[c as usize];
        if b != NONE {
            boundary_out[corner_vertex[next_c(c) as usize] as usize] = b;
            boundary_in[corner_vertex[c as usize] as usize] = b;
        }
    }
    (boundary_out, boundary_in)
}

/// Per vertex the first corner at it.
fn first_corners(corner_vertex: &[u32], n_vertices: usize) -> Vec<u32> {
    let mut first_corner = vec![NONE; n_vertices];
    for (c, &v) in corner_vertex.iter().enumerate() {
        let f = &mut first_corner[v as usize];
        if *f == NONE {
            *f = c as u32;
        }
    }
    first_corner
}

/// Vertex `i` at the position of its input vertex; its half-edge is its boundary out-going
/// one, else its first corner's.
fn insert_vertices(
    vertices: &mut SlotMap<VertexId, VertexRecord>,
    positions: &[DVec3],
    vertex_source: &[u32],
    links: &Links,
) {
    vertices.reserve(vertex_source.len());
    for (i, &s) in vertex_source.iter().enumerate() {
        let halfedge = if links.boundary_out[i] != NONE {
            Some(fresh_key(links.boundary_out[i] as usize))
        } else if links.first_corner[i] != NONE {
            Some(fresh_key(links.first_corner[i] as usize))
        } else {
            None
        };
        let _k = vertices.insert(VertexRecord {
            halfedge,
            position: positions[s as usize],
        });
        debug_assert_eq!(_k, fresh_key(i));
    }
}

/// Face `t` stores half-edge `3t`.
fn insert_faces(faces: &mut SlotMap<FaceId, FaceRecord>, nt: usize) {
    faces.reserve(nt);
    for t in 0..nt {
        let _k = faces.insert(FaceRecord {
            halfedge: fresh_key(3 * t),
        });
        debug_assert_eq!(_k, fresh_key::<FaceId>(t));
    }
}

/// The interior half-edges in corner order, then the boundary ones.
fn insert_halfedges(
    halfedges: &mut SlotMap<HalfedgeId, HalfedgeRecord>,
    corners: &CornerTable,
    links: &Links,
) {
    let CornerTable {
        corner_vertex,
        mate,
    } = corners;
    let nh = corner_vertex.len();
    halfedges.reserve(nh + links.n_boundary as usize);
    for c in 0..nh as u32 {
        let m = mate[c as usize];
        let twin = if m != NONE {
            m
        } else {
            links.boundary_index[c as usize]
        };
        let _k = halfedges.insert(HalfedgeRecord {
            to: fresh_key(corner_vertex[next_c(c) as usize] as usize),
            next: fresh_key(next_c(c) as usize),
            prev: fresh_key(prev_c(c) as usize),
            twin: fresh_key(twin as usize),
            face: Some(fresh_key((c / 3) as usize)),
        });
        debug_assert_eq!(_k, fresh_key(c as usize));
    }
    for c in 0..nh as u32 {
        let b = links.boundary_index[c as usize];
        if b == NONE {
            continue;
        }
        // b runs from c's head back to c's tail; the boundary loop goes on from the
        // tail and comes in at the head.
        let tail = corner_vertex[c as usize] as usize;
        let head = corner_vertex[next_c(c) as usize] as usize;
        let _k = halfedges.insert(HalfedgeRecord {
            to: fresh_key(tail),
            next: fresh_key(links.boundary_out[tail] as usize),
            prev: fresh_key(links.boundary_in[head] as usize),
            twin: fresh_key(c as usize),
            face: None,
        });
        debug_assert_eq!(_k, fresh_key(b as usize));
    }
}
