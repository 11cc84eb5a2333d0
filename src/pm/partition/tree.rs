//! The merge tree of a partitioned build: which block holds each input face, which of a
//! block's vertices are pinned, and how much of the input each block covers.
//!
//! The cells (`cells.rs`) are the leaves of a complete binary tree; node `k` of level `j`
//! covers cells `k·2^j .. (k+1)·2^j` and merges nodes `2k` and `2k+1` of level `j - 1`.
//!
//! - A face belongs to the lowest node that covers the cells of all three of its vertices:
//!   faces inside a cell belong to the leaf, a face across cells joins the decimation at the
//!   node where its cells meet.
//! - A vertex is free in a node when every input face around it (its star) lies in the node,
//!   else pinned. Stars only grow by collapses inside one node, so a free vertex's faces stay
//!   inside its node for the whole decimation, and no two nodes of a level share a free
//!   vertex or a face.

/// The tree over the cells, with the input faces sorted into its nodes.
pub(crate) struct MergeTree {
    /// Levels above the leaves (the root is level `depth`).
    pub depth: u32,
    /// For each vertex, the smallest and largest cell among the vertices of its star
    /// (`u32::MAX, 0` for a vertex without faces).
    star: Vec<(u32, u32)>,
    /// `joined[j][k]`: the input faces that first lie inside node `k` of level `j`, in input
    /// order.
    joined: Vec<Vec<Vec<u32>>>,
}

impl MergeTree {
    /// The tree of `depth` levels over the cells `cell_of` for the triangles `faces`.
    pub(crate) fn new(cell_of: &[u32], depth: u32, faces: &[[u32; 3]]) -> MergeTree {
        let n_cells = 1usize << depth;
        let mut star = vec![(u32::MAX, 0u32); cell_of.len()];
        let mut joined: Vec<Vec<Vec<u32>>> = (0..=depth)
            .map(|j| vec![Vec::new(); n_cells >> j])
            .collect();
        for (t, f) in faces.iter().enumerate() {
            let cells = f.map(|v| cell_of[v as usize]);
            let (lo, hi) = (cells.iter().min().copied(), cells.iter().max().copied());
            let (lo, hi) = (lo.unwrap_or(0), hi.unwrap_or(0));
            for &v in f {
                let s = &mut star[v as usize];
                *s = (s.0.min(lo), s.1.max(hi));
            }
            let level = 32 - (lo ^ hi).leading_zeros();
            joined[level as usize][(lo >> level) as usize].push(t as u32);
        }
        MergeTree {
            depth,
            star,
            joined,
        }
    }

    /// Number of nodes at level `j`.
    pub(crate) fn nodes_at(&self, j: u32) -> usize {
        1 << (self.depth - j)
    }

    /// The cells node `k` of level `j` covers.
    fn cells(&self, j: u32, k: usize) -> std::ops::Range<usize> {
        k << j..(k + 1) << j
    }

    /// The input faces that join the decimation at node `k` of level `j`.
    pub(crate) fn joined(&self, j: u32, k: usize) -> &[u32] {
        &self.joined[j as usize][k]
    }

    /// Whether vertex `v` is pinned in node `k` of level `j`: some face of its star lies
    /// outside the node.
    pub(crate) fn is_pinned(&self, j: u32, k: usize, v: u32) -> bool {
        let (lo, hi) = self.star[v as usize];
        let cells = self.cells(j, k);
        !(cells.contains(&(lo as usize)) && cells.contains(&(hi as usize)))
    }

    /// Number of input faces inside node `k` of level `j` (its own and its descendants').
    pub(crate) fn faces_in(&self, j: u32, k: usize) -> usize {
        (0..=j)
            .map(|i| {
                let per = 1usize << (j - i);
                (k * per..(k + 1) * per)
                    .map(|m| self.joined[i as usize][m].len())
                    .sum::<usize>()
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of 6 vertices, 4 triangles, cut into 4 cells: 0 1 | 2 | 3 | 4 5 along it.
    ///
    /// ```text
    /// 0 - 2 - 4
    /// | / | / |
    /// 1 - 3 - 5
    /// ```
    fn strip() -> MergeTree {
        let cell_of = [0, 0, 1, 2, 3, 3];
        let faces = [[0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5]];
        MergeTree::new(&cell_of, 2, &faces)
    }

    #[test]
    fn faces_join_where_their_cells_meet() {
        let t = strip();
        assert_eq!(t.joined(1, 0), &[0]); // cells 0, 1
        assert_eq!(t.joined(2, 0), &[1, 2]); // cells 0..=2 and 1..=3
        assert_eq!(t.joined(1, 1), &[3]); // cells 2, 3
        assert!(t.joined(0, 0).is_empty());
        assert_eq!(t.faces_in(2, 0), 4);
        assert_eq!(t.faces_in(1, 0), 1);
    }

    #[test]
    fn a_vertex_is_free_where_its_whole_star_is() {
        let t = strip();
        assert!(t.is_pinned(1, 0, 1)); // its star reaches cell 2
        assert!(!t.is_pinned(1, 1, 5));
        assert!(!t.is_pinned(2, 0, 2));
    }
}
