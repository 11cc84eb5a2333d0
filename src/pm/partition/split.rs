//! One pass's blocks: the current faces sorted into the cells of the pass (`cells.rs`), and
//! which vertices are pinned.
//!
//! - A face whose three vertices lie in one cell belongs to that cell's block; a face across
//!   cells belongs to no block in this pass and stays as it is.
//! - A vertex is pinned in this pass when a face of its star lies across cells; every other
//!   vertex is free and its whole star is inside its own block. A collapse of two free
//!   vertices only moves faces between their stars, so during the pass no two blocks share a
//!   free vertex or a face.

/// The current faces of the whole mesh split for one pass.
pub(crate) struct Split {
    /// Per cell, the faces inside it, in the order of the whole mesh's list.
    pub inside: Vec<Vec<[u32; 3]>>,
    /// The faces across cells, in the same order.
    pub across: Vec<[u32; 3]>,
    /// Per vertex (input index), whether a face across cells touches it.
    pub pinned: Vec<bool>,
    /// With the faces' corners' wedges (a textured scan): those of `inside` and `across`, face
    /// for face (else empty).
    pub inside_wedges: Vec<Vec<[u32; 3]>>,
    pub across_wedges: Vec<[u32; 3]>,
}

/// Splits `faces`, and `wedges` (per face its corners' wedges, or empty), by the cells
/// `cell_of` (`n_cells` of them) of their vertices.
pub(crate) fn split_faces(
    faces: &[[u32; 3]],
    wedges: &[[u32; 3]],
    cell_of: &[u32],
    n_cells: usize,
) -> Split {
    let mut inside: Vec<Vec<[u32; 3]>> = vec![Vec::new(); n_cells];
    let mut across = Vec::new();
    let mut pinned = vec![false; cell_of.len()];
    let with_wedges = !wedges.is_empty();
    let mut inside_wedges: Vec<Vec<[u32; 3]>> =
        vec![Vec::new(); if with_wedges { n_cells } else { 0 }];
    let mut across_wedges = Vec::new();
    for (i, &f) in faces.iter().enumerate() {
        let [a, b, c] = f.map(|v| cell_of[v as usize]);
        if a == b && b == c {
            inside[a as usize].push(f);
            if with_wedges {
                inside_wedges[a as usize].push(wedges[i]);
            }
        } else {
            across.push(f);
            if with_wedges {
                across_wedges.push(wedges[i]);
            }
            for v in f {
                pinned[v as usize] = true;
            }
        }
    }
    Split {
        inside,
        across,
        pinned,
        inside_wedges,
        across_wedges,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of 6 vertices, 4 triangles, cut into 3 cells: 0 1 | 2 3 | 4 5 across it.
    ///
    /// ```text
    /// 0 - 2 - 4
    /// | / | / |
    /// 1 - 3 - 5
    /// ```
    #[test]
    fn faces_across_cells_pin_their_vertices_and_belong_to_no_block() {
        let cell_of = [0, 0, 1, 1, 2, 2];
        let faces = [[0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5]];
        let s = split_faces(&faces, &[], &cell_of, 3);
        assert!(s.inside.iter().all(Vec::is_empty));
        assert_eq!(s.across.len(), 4);
        assert!(s.pinned.iter().all(|&p| p));
        let cell_of = [0, 0, 0, 0, 1, 1];
        let s = split_faces(&faces, &[], &cell_of, 2);
        assert_eq!(s.inside[0], vec![[0, 1, 2], [2, 1, 3]]);
        assert!(s.inside[1].is_empty());
        assert_eq!(s.across, vec![[2, 3, 4], [4, 3, 5]]);
        assert_eq!(s.pinned, vec![false, false, true, true, true, true]);
    }
}
