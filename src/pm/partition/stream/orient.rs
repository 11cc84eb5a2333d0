//! The orientation round of the cell tasks: the builder's choice of each component's
//! orientation, made from every cell's patches by a union–find on the driver.
//!
//! The builder walks each component (triangles joined by paired edges) breadth first from its
//! first triangle, flipping a triangle whose pair runs the same way as its neighbour's, then
//! flips the whole component when more than half of it was flipped. So a triangle ends flipped
//! when its parity (flips along any path) from the component's first triangle differs from
//! that triangle's, exclusive-or the component's majority. Steps:
//! 1. each cell ([`cell_patches`]) joins the triangles of its `face` file along the pairs it
//!    sees into patches, with each triangle's parity to its patch (a union–find with parity),
//!    and reports per patch the triangles it owns by parity and its first owned triangle, and
//!    for every triangle with a vertex in another cell its patch and parity (the other cells
//!    see it too: that is how patches of different cells join);
//! 2. the driver ([`orient`]) joins the patches through the triangles they share, and per
//!    component finds the first triangle and the majority: one flip bit per patch;
//! 3. the later rounds flip a triangle when its patch's bit differs from its parity.
//!
//! A component that cannot be oriented (a Möbius band: an odd cycle of parities) is refused:
//! the builder cuts the edge its walk meets first, which no cell can know.

use super::cell::Cell;
use super::files::{Manifest, cell_paths};
use super::rounds::{FLIPS, PATCHES, SHARED, read_words, words_section};
use super::{GlobalRepair, SplitError};
use crate::pm::partition::taskfile::{BlockFileError, Section, TaskFile};
use std::path::Path;

const NONE: u32 = u32::MAX;

/// A patch's share of its component: the triangles the cell owns in it with parity 0 and 1
/// to the patch's root, and the first of them with its parity.
type Patch = ([u64; 2], Option<(u64, u8)>);

/// One cell's patches, for [`orient`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CellPatches {
    /// Per patch, its share.
    patches: Vec<Patch>,
    /// `(triangle, patch, parity)` of every triangle with a vertex in another cell.
    shared: Vec<(u64, u32, u8)>,
}

/// The flip of every cell's patches (from [`orient`]): a triangle is flipped when its patch's
/// bit differs from its parity.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Flips {
    cells: Vec<Vec<bool>>,
}

impl Flips {
    /// Whether patch `patch` of cell `k` flips its parity-0 triangles (nothing flips when the
    /// round was not run).
    pub(super) fn of(&self, k: u32, patch: u32) -> bool {
        let cell = self.cells.get(k as usize);
        cell.and_then(|c| c.get(patch as usize))
            .copied()
            .unwrap_or(false)
    }
}

impl CellPatches {
    /// The round file's sections of these patches (`rounds.rs`).
    pub(super) fn sections(&self) -> Vec<Section> {
        let mut p = Vec::with_capacity(4 * self.patches.len());
        for (counts, first) in &self.patches {
            let (t, parity) = first.map_or((u64::MAX, 0), |(t, q)| (t, q as u64));
            p.extend([counts[0], counts[1], t, parity]);
        }
        let mut s = Vec::with_capacity(3 * self.shared.len());
        for &(t, q, parity) in &self.shared {
            s.extend([t, q as u64, parity as u64]);
        }
        vec![words_section(PATCHES, 0, &p), words_section(SHARED, 0, &s)]
    }

    /// The patches of a patches round file, checked: parities 0 or 1, patches in range.
    pub(super) fn read(f: &mut TaskFile) -> Result<CellPatches, BlockFileError> {
        let (p, at) = read_words(f, PATCHES, 0)?;
        let (s, at_shared) = read_words(f, SHARED, 0)?;
        if p.len() % 4 != 0 || s.len() % 3 != 0 {
            return Err(f.error(at, "patches or shared triangles of a partial record"));
        }
        let mut out = CellPatches::default();
        for (i, r) in p.chunks_exact(4).enumerate() {
            if r[3] > 1 {
                return Err(f.error(at + 32 * i as u64, "a parity other than 0 or 1"));
            }
            let first = (r[2] != u64::MAX).then_some((r[2], r[3] as u8));
            out.patches.push(([r[0], r[1]], first));
        }
        for (i, r) in s.chunks_exact(3).enumerate() {
            if r[1] >= out.patches.len() as u64 || r[2] > 1 {
                let what = "a shared triangle of no patch or with a parity other than 0 or 1";
                return Err(f.error(at_shared + 24 * i as u64, what));
            }
            out.shared.push((r[0], r[1] as u32, r[2] as u8));
        }
        Ok(out)
    }
}

impl Flips {
    /// The flips file's sections: one per cell (`rounds.rs`).
    pub(super) fn sections(&self) -> Vec<Section> {
        let cell = |(k, bits): (usize, &Vec<bool>)| {
            let words: Vec<u64> = bits.iter().map(|&b| b as u64).collect();
            words_section(FLIPS, k as u32, &words)
        };
        self.cells.iter().enumerate().map(cell).collect()
    }

    /// Cell `k`'s flips from a flips file (the other cells' left out: a cell task reads only
    /// its own).
    pub(super) fn read_cell(f: &mut TaskFile, k: u32) -> Result<Flips, BlockFileError> {
        let (words, at) = read_words(f, FLIPS, k)?;
        if let Some(i) = words.iter().position(|&w| w > 1) {
            return Err(f.error(at + 8 * i as u64, "a flip other than 0 or 1"));
        }
        let mut cells = vec![Vec::new(); k as usize];
        cells.push(words.iter().map(|&w| w == 1).collect());
        Ok(Flips { cells })
    }
}

/// A union–find whose nodes carry their parity to their parent.
struct Parity {
    parent: Vec<u32>,
    parity: Vec<u8>,
}

impl Parity {
    fn new(n: usize) -> Parity {
        Parity {
            parent: (0..n as u32).collect(),
            parity: vec![0; n],
        }
    }

    /// The root of `x` and `x`'s parity to it.
    fn find(&mut self, x: u32) -> (u32, u8) {
        let mut path = Vec::new();
        let mut r = x;
        while self.parent[r as usize] != r {
            path.push(r);
            r = self.parent[r as usize];
        }
        // Compress from the node nearest the root, so that each parity is to the root.
        let mut to_root = 0u8;
        for &y in path.iter().rev() {
            to_root ^= self.parity[y as usize];
            self.parity[y as usize] = to_root;
            self.parent[y as usize] = r;
        }
        (r, if x == r { 0 } else { self.parity[x as usize] })
    }

    /// Joins `a` and `b` with parity `p` between them; false when that contradicts what is
    /// known (an odd cycle).
    fn union(&mut self, a: u32, b: u32, p: u8) -> bool {
        let ((ra, pa), (rb, pb)) = (self.find(a), self.find(b));
        if ra == rb {
            return pa ^ pb == p;
        }
        self.parent[ra as usize] = rb;
        self.parity[ra as usize] = pa ^ pb ^ p;
        true
    }
}

/// Step 1 within a cell: the patch of every local triangle (numbered by first triangle) and
/// its parity to the patch's root.
pub(super) fn local_patches(cell: &Cell) -> Result<(Vec<u32>, Vec<u8>), SplitError> {
    let n = cell.faces.len();
    let mut uf = Parity::new(n);
    for c in 0..3 * n as u32 {
        let m = cell.mate[c as usize];
        if m == NONE || m < c {
            continue;
        }
        let p = (cell.vertex(c) == cell.vertex(m)) as u8;
        if !uf.union(c / 3, m / 3, p) {
            return Err(unorientable(&cell.face_path, cell.at((c / 3) as usize)));
        }
    }
    let mut patch_of_root = vec![NONE; n];
    let (mut patch, mut parity) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut next = 0u32;
    for i in 0..n as u32 {
        let (r, p) = uf.find(i);
        if patch_of_root[r as usize] == NONE {
            patch_of_root[r as usize] = next;
            next += 1;
        }
        patch.push(patch_of_root[r as usize]);
        parity.push(p);
    }
    Ok((patch, parity))
}

fn unorientable(path: &Path, offset: u64) -> SplitError {
    SplitError::NotLocal {
        path: path.to_path_buf(),
        offset,
        repair: GlobalRepair::Orientation,
        what: "a component cannot be oriented (a Möbius band): the mesh builder cuts the edge \
               its walk meets first, which the cells cannot know; build this scan in one \
               process"
            .into(),
    }
}

/// Round 1 of the cell tasks: cell `k`'s patches (step 1 of the module docs).
pub fn cell_patches(dir: &Path, manifest: &Manifest, k: u32) -> Result<CellPatches, SplitError> {
    let cell = Cell::read(dir, manifest, k)?;
    let (patch, parity) = local_patches(&cell)?;
    let n_patches = patch.iter().max().map_or(0, |&p| p as usize + 1);
    let mut out = CellPatches {
        patches: vec![([0; 2], None); n_patches],
        shared: Vec::new(),
    };
    for (i, f) in cell.faces.iter().enumerate() {
        let (q, p) = (patch[i], parity[i]);
        if f.owner == k {
            let entry = &mut out.patches[q as usize];
            entry.0[p as usize] += 1;
            entry.1.get_or_insert((f.triangle, p));
        }
        if !f.vertices.iter().all(|&v| cell.is_own(v)) {
            out.shared.push((f.triangle, q, p));
        }
    }
    Ok(out)
}

/// Step 2, on the driver: the flip of every patch of every cell from all cells' patches (in
/// cell order), as the builder orients each component. `dir` names the cells' files in a
/// refusal.
pub fn orient(dir: &Path, patches: &[CellPatches]) -> Result<Flips, SplitError> {
    let mut first = Vec::with_capacity(patches.len());
    let mut n = 0usize;
    for p in patches {
        first.push(n as u32);
        n += p.patches.len();
    }
    let mut uf = Parity::new(n);
    let mut shared: Vec<(u64, u32, u8, u32)> = Vec::new();
    for (k, p) in patches.iter().enumerate() {
        let node = |q: u32| first[k] + q;
        shared.extend(
            p.shared
                .iter()
                .map(|&(t, q, par)| (t, node(q), par, k as u32)),
        );
    }
    shared.sort_unstable();
    for run in shared.chunk_by(|a, b| a.0 == b.0) {
        let (_, a, pa, _) = run[0];
        for &(_, b, pb, k) in &run[1..] {
            if !uf.union(a, b, pa ^ pb) {
                let [_, face, _] = cell_paths(dir, k as usize);
                return Err(unorientable(&face, 0));
            }
        }
    }
    // Per component (by root): the first triangle with its parity to the root, and the
    // triangles by parity to the root.
    let mut seed: Vec<Option<(u64, u8)>> = vec![None; n];
    let mut counts = vec![[0u64; 2]; n];
    for (k, p) in patches.iter().enumerate() {
        for (q, (c, s)) in p.patches.iter().enumerate() {
            let (r, to_root) = uf.find(first[k] + q as u32);
            let r = r as usize;
            counts[r][to_root as usize] += c[0];
            counts[r][1 - to_root as usize] += c[1];
            if let Some((t, par)) = *s
                && seed[r].is_none_or(|(best, _)| t < best)
            {
                seed[r] = Some((t, par ^ to_root));
            }
        }
    }
    let mut cells = Vec::with_capacity(patches.len());
    for (k, p) in patches.iter().enumerate() {
        let bits = (0..p.patches.len() as u32).map(|q| {
            let (r, to_root) = uf.find(first[k] + q);
            let r = r as usize;
            let seed_parity = seed[r].map_or(0, |s| s.1);
            let flipped = counts[r][1 - seed_parity as usize];
            let invert = 2 * flipped > counts[r][0] + counts[r][1];
            // The patch's parity-0 triangles are flipped when their parity to the seed is odd,
            // exclusive-or the majority.
            (to_root ^ seed_parity == 1) ^ invert
        });
        cells.push(bits.collect());
    }
    Ok(Flips { cells })
}
