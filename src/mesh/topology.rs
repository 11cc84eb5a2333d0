//! Global topology of a [`Mesh`]: components, boundary loops, Euler characteristic, genus.

use super::halfedge::{Mesh, SlotIndex};
use super::union_find::UnionFind;
use serde::Serialize;

/// Counts describing a mesh's topology.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Topology {
    /// Vertices with at least one edge.
    pub referenced_vertices: usize,
    /// Edges.
    pub edges: usize,
    /// Triangles.
    pub faces: usize,
    /// Closed loops of boundary half-edges (holes).
    pub boundary_loops: usize,
    /// Edge-connected components of faces (isolated vertices not counted).
    pub components: usize,
    /// V − E + F over referenced vertices.
    pub euler_characteristic: i64,
    /// Σ over components of (2 − b − χ)/2; `None` if a component's value is not a whole
    /// non-negative number (which a valid orientable surface never gives).
    pub genus: Option<u64>,
    /// The fewest vertices a triangulation of the same surface can have, summed over
    /// components (`vertex_floor`): how far a simplification can go at most.
    pub floor_vertices: usize,
}

/// The fewest vertices a triangulated component with `genus` handles and `boundary_loops`
/// holes can have: 4 for a sphere (a tetrahedron), Heawood's bound `⌈(7 + √(1 + 48g)) / 2⌉`
/// for a closed surface of genus `g ≥ 1` (7 for a torus), and with holes, at least 3 per
/// hole (a hole is a cycle of at least 3 edges) and at least the closed surface's bound minus
/// one per hole (capping every hole with one vertex gives a closed surface).
pub(crate) fn vertex_floor(genus: u64, boundary_loops: u64) -> u64 {
    let closed = if genus == 0 {
        4
    } else {
        ((7.0 + (1.0 + 48.0 * genus as f64).sqrt()) / 2.0).ceil() as u64
    };
    if boundary_loops == 0 {
        closed
    } else {
        (3 * boundary_loops)
            .max(closed.saturating_sub(boundary_loops))
            .max(3)
    }
}

impl Topology {
    /// The floor and what sets it, for reports: "318 vertices (1 component, 106 holes,
    /// genus 3)".
    pub(crate) fn describe_floor(&self) -> String {
        let count =
            |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        let genus = self
            .genus
            .map_or("genus n/a".to_string(), |g| format!("genus {g}"));
        format!(
            "{} ({}, {}, {genus})",
            count(self.floor_vertices, "vertex", "vertices"),
            count(self.components, "component", "components"),
            count(self.boundary_loops, "hole", "holes"),
        )
    }
}

impl Mesh {
    /// Computes the [`Topology`] summary in linear time.
    pub fn topology(&self) -> Topology {
        // Components by union-find over vertex slots, joined along edges.
        let n = self.vertices.capacity() + 1;
        let mut parent = UnionFind::new(n);
        for h in self.edges() {
            parent.union(
                self.from_vertex(h).slot() as u32,
                self.to_vertex(h).slot() as u32,
            );
        }
        // Per-component counts (V, E, F, B), keyed by root slot.
        let mut comp_index = vec![u32::MAX; n];
        let mut counts: Vec<[i64; 4]> = Vec::new();
        let mut comp_of = |parent: &mut UnionFind, slot: usize, counts: &mut Vec<[i64; 4]>| {
            let r = parent.find(slot as u32) as usize;
            if comp_index[r] == u32::MAX {
                comp_index[r] = counts.len() as u32;
                counts.push([0; 4]);
            }
            comp_index[r] as usize
        };
        let mut referenced = 0;
        for v in self.vertices() {
            if !self.is_isolated(v) {
                referenced += 1;
                let c = comp_of(&mut parent, v.slot(), &mut counts);
                counts[c][0] += 1;
            }
        }
        for h in self.edges() {
            let c = comp_of(&mut parent, self.from_vertex(h).slot(), &mut counts);
            counts[c][1] += 1;
        }
        for f in self.faces() {
            let v = self.face_vertices(f)[0];
            let c = comp_of(&mut parent, v.slot(), &mut counts);
            counts[c][2] += 1;
        }
        // Boundary loops: walk each unvisited boundary half-edge's loop once.
        let mut seen = vec![false; self.halfedges.capacity() + 1];
        let mut loops = 0;
        for h in self.halfedges() {
            if !self.is_boundary_halfedge(h) || seen[h.slot()] {
                continue;
            }
            loops += 1;
            let c = comp_of(&mut parent, self.from_vertex(h).slot(), &mut counts);
            counts[c][3] += 1;
            let mut g = h;
            while !seen[g.slot()] {
                seen[g.slot()] = true;
                g = self.next(g);
            }
        }
        let mut genus = Some(0u64);
        let mut chi_total = 0;
        let mut floor_vertices = 0;
        for &[v, e, f, b] in &counts {
            let chi = v - e + f;
            chi_total += chi;
            let twice = 2 - b - chi;
            let whole = twice >= 0 && twice % 2 == 0;
            genus = match genus {
                Some(g) if whole => Some(g + (twice / 2) as u64),
                _ => None,
            };
            // A component whose genus is not whole cannot be a valid surface; count it as
            // the sphere it would be with its holes.
            let g = if whole { (twice / 2) as u64 } else { 0 };
            floor_vertices += vertex_floor(g, b as u64).min(v as u64) as usize;
        }
        Topology {
            referenced_vertices: referenced,
            edges: self.n_edges(),
            faces: self.n_faces(),
            boundary_loops: loops,
            components: counts.len(),
            euler_characteristic: chi_total,
            genus,
            floor_vertices,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_floor_of_closed_surfaces_is_the_smallest_triangulation() {
        assert_eq!(vertex_floor(0, 0), 4); // tetrahedron
        assert_eq!(vertex_floor(1, 0), 7); // Möbius–Császár torus
        assert_eq!(vertex_floor(2, 0), 9); // Heawood's bound (10 is realised)
        assert_eq!(vertex_floor(6, 0), 12);
    }

    #[test]
    fn holes_need_three_vertices_each() {
        assert_eq!(vertex_floor(0, 1), 3); // a single triangle
        assert_eq!(vertex_floor(0, 2), 6); // an annulus between two triangles
        assert_eq!(vertex_floor(3, 106), 318);
        assert_eq!(vertex_floor(6, 1), 11);
    }
}
