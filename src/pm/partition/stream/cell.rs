//! The cell tasks of the streaming split: from one cell's files (its vertices, every triangle
//! that touches them, the positions of those triangles' other vertices), the mesh builder's
//! local repairs and the initial quadrics of the cell's vertices, written as a first piece of
//! the partitioned build through files.
//!
//! Steps (each round reads the cell again: a task keeps nothing between rounds):
//! 1. **pairing**: the half-edges of every edge with an end in the cell, grouped by edge and
//!    paired as the builder pairs them (two triangles: with each other; more: by angle about
//!    the edge, `pair_around_edge`, the builder's code) — the cell holds every triangle
//!    around its vertices, so it sees each such edge whole. Then the triangles are flipped as
//!    the orientation round decided (`orient.rs`, [`Flips`]; nothing before that round);
//! 2. **fans** ([`cell_fans`]): each of the cell's vertices walked fan by fan (`walk_fan`, the
//!    builder's code); the fan with the vertex's first corner keeps it, every other fan is a
//!    copy. The builder numbers copies after the input's vertices in the order of their fans'
//!    first corners over the whole mesh, so the copies' numbers are given by the driver
//!    ([`number_copies`]) from every cell's fans;
//! 3. **multi-edges**: two distinct edges between the same two vertices after the fans are
//!    split would make the builder detach one end: refused;
//! 4. **quadrics**: each of the cell's vertices (and copies) sums the planes of its triangles
//!    in triangle order, then its point regulariser, then the planes of its boundary edges in
//!    corner order, in the frame centred on the manifest's bounding box of used vertices —
//!    the order and the operations of `initial_quadrics`, so the same bits;
//! 5. **the piece** ([`cell_piece`]): the triangles the cell owns, in triangle order, and the records of its
//!    vertices with triangles, ascending (copies after the input's vertices).
//!
//! The corners keep the builder's numbers (`3t + k` for corner `k` of triangle `t`), so ties
//! (angles, first corners) are broken as the builder breaks them.

use super::files::{FaceRecord, Manifest, cell_paths, read_faces, read_vertices};
use super::orient::{Flips, local_patches};
use super::rounds::{COPIES, read_words, words_section};
use super::{GlobalRepair, SplitError};
use crate::mesh::BoundingBox;
use crate::mesh::build::{next_c, pair_around_edge, walk_fan};
use crate::pm::partition::block::VertexQuadric;
use crate::pm::partition::contents::{self, Record};
use crate::pm::partition::taskfile::{BlockFileError, Section, TaskFile};
use crate::pm::quadric::{POINT_REGULARISATION, Quadric};
use glam::DVec3;
use std::path::{Path, PathBuf};

const NONE: u32 = u32::MAX;

/// A vertex's fan other than its first: a copy of the vertex in the repaired mesh.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExtraFan {
    /// Its first corner (the builder's corner number), which orders the copies.
    pub first: u32,
    /// All its corners, ascending.
    pub corners: Vec<u32>,
}

/// The repaired mesh's vertex of every corner in an extra fan (the copies), from
/// [`number_copies`]; every other corner keeps its input vertex.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Copies {
    /// `(corner, vertex)`, ascending by corner.
    corners: Vec<(u32, u32)>,
    /// The repaired mesh's vertex count (the input's and the copies).
    pub n_vertices: u64,
}

impl Copies {
    /// The copies file's section (`rounds.rs`).
    pub(super) fn section(&self) -> Section {
        let mut words = Vec::with_capacity(1 + 2 * self.corners.len());
        words.push(self.n_vertices);
        words.extend(self.corners.iter().flat_map(|&(c, v)| [c as u64, v as u64]));
        words_section(COPIES, 0, &words)
    }

    /// The copies of a copies file, checked: pairs ascending by corner, copies numbered
    /// below the vertex count.
    pub(super) fn read(f: &mut TaskFile) -> Result<Copies, BlockFileError> {
        let (words, at) = read_words(f, COPIES, 0)?;
        let Some((&n_vertices, pairs)) = words.split_first() else {
            return Err(f.error(at, "no vertex count"));
        };
        if pairs.len() % 2 != 0 || n_vertices >= NONE as u64 {
            return Err(f.error(at, "a partial pair or a vertex count past 32 bits"));
        }
        let mut corners = Vec::with_capacity(pairs.len() / 2);
        for (i, p) in pairs.chunks_exact(2).enumerate() {
            let ascending = corners.last().is_none_or(|&(c, _)| (c as u64) < p[0]);
            if p[0] >= NONE as u64 || p[1] >= n_vertices || !ascending {
                let what = "a corner out of order or a copy past the vertex count";
                return Err(f.error(at + 8 + 16 * i as u64, what));
            }
            corners.push((p[0] as u32, p[1] as u32));
        }
        Ok(Copies {
            corners,
            n_vertices,
        })
    }

    fn of(&self, corner: u32) -> Option<u32> {
        let i = self.corners.binary_search_by_key(&corner, |x| x.0).ok()?;
        Some(self.corners[i].1)
    }
}

/// Numbers the copies of every cell's extra fans as the builder does: after the input's
/// `input_vertices` vertices, in the order of their first corners. Fails as the builder does
/// when the vertices would not fit 32-bit indices.
pub fn number_copies(input_vertices: u64, mut fans: Vec<ExtraFan>) -> Result<Copies, SplitError> {
    if input_vertices + fans.len() as u64 >= NONE as u64 {
        let e = crate::pm::PmError::Mesh(crate::mesh::BuildError::TooLarge);
        return Err(e.into());
    }
    fans.sort_unstable_by_key(|f| f.first);
    let mut corners = Vec::new();
    for (i, f) in fans.iter().enumerate() {
        let v = (input_vertices + i as u64) as u32;
        corners.extend(f.corners.iter().map(|&c| (c, v)));
    }
    corners.sort_unstable();
    Ok(Copies {
        corners,
        n_vertices: input_vertices + fans.len() as u64,
    })
}

/// What a cell's piece holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PieceCounts {
    /// Its triangles.
    pub faces: u64,
    /// Its vertex records.
    pub vertices: u64,
}

/// One cell's files, read and checked, with its half-edges paired.
pub(super) struct Cell {
    /// The `face` file (for messages).
    pub(super) face_path: PathBuf,
    own: Vec<(u32, DVec3)>,
    border: Vec<(u32, DVec3)>,
    pub(super) faces: Vec<FaceRecord>,
    /// Mate of every local corner `3i + k` (triangle `i` of `faces`); `NONE` on a boundary
    /// and on edges without an end in the cell, which the cell does not see whole.
    pub(super) mate: Vec<u32>,
    /// Whether each local corner's vertex is one of the cell's.
    own_at: Vec<bool>,
}

impl Cell {
    /// Reads cell `k` of the split described by `manifest` in `dir`, and pairs its edges.
    pub(super) fn read(dir: &Path, manifest: &Manifest, k: u32) -> Result<Cell, SplitError> {
        let entry = manifest.cells.get(k as usize).ok_or_else(|| {
            let what = format!("cell {k} of {}", manifest.cells.len());
            SplitError::File(super::BlockFileError::new(&dir.join("manifest"), 0, what))
        })?;
        let [vert, face, border] = cell_paths(dir, k as usize);
        let own = read_vertices(&vert, entry.vertices, entry.crc[0])?;
        let border_v = read_vertices(&border, entry.border, entry.crc[2])?;
        let faces = read_faces(&face, entry, manifest.cells.len() as u32)?;
        let mut cell = Cell {
            face_path: face,
            own,
            border: border_v,
            faces,
            mate: Vec::new(),
            own_at: Vec::new(),
        };
        cell.check(manifest)?;
        let corners = 0..3 * cell.faces.len() as u32;
        cell.own_at = corners.map(|c| cell.is_own(cell.vertex(c))).collect();
        cell.pair();
        Ok(cell)
    }

    pub(super) fn is_own(&self, v: u32) -> bool {
        self.own.binary_search_by_key(&v, |x| x.0).is_ok()
    }

    fn position(&self, v: u32) -> DVec3 {
        match self.own.binary_search_by_key(&v, |x| x.0) {
            Ok(i) => self.own[i].1,
            Err(_) => {
                let i = self.border.binary_search_by_key(&v, |x| x.0);
                i.map_or(DVec3::NAN, |i| self.border[i].1)
            }
        }
    }

    pub(super) fn at(&self, i: usize) -> u64 {
        (i * super::files::RECORD) as u64
    }

    /// Every triangle touches the cell, every vertex has a position, triangles are numbered
    /// within the manifest's count.
    fn check(&self, manifest: &Manifest) -> Result<(), SplitError> {
        let known =
            |v: u32| self.is_own(v) || self.border.binary_search_by_key(&v, |x| x.0).is_ok();
        for (i, f) in self.faces.iter().enumerate() {
            let touches = f.vertices.iter().any(|&v| self.is_own(v));
            let all_known = f.vertices.iter().all(|&v| known(v));
            if !touches || !all_known || f.triangle >= manifest.triangles {
                let what = format!(
                    "triangle {} does not touch the cell, has a vertex without a position, or \
                     is past the manifest's {} triangles",
                    f.triangle, manifest.triangles
                );
                let e = super::BlockFileError::new(&self.face_path, self.at(i), what);
                return Err(e.into());
            }
        }
        Ok(())
    }

    /// The builder's corner number of local corner `c`.
    fn corner(&self, c: u32) -> u32 {
        3 * self.faces[(c / 3) as usize].triangle as u32 + c % 3
    }

    /// The input vertex of local corner `c`.
    pub(super) fn vertex(&self, c: u32) -> u32 {
        self.faces[(c / 3) as usize].vertices[(c % 3) as usize]
    }

    /// Step 1: pairs the half-edges of every edge with an end in the cell.
    fn pair(&mut self) {
        let n = 3 * self.faces.len() as u32;
        let mut edges: Vec<(u64, u32)> = Vec::new();
        for c in 0..n {
            let (a, b) = (self.vertex(c), self.vertex(next_c(c)));
            if self.own_at[c as usize] || self.own_at[next_c(c) as usize] {
                edges.push(((a.min(b) as u64) << 32 | a.max(b) as u64, c));
            }
        }
        // Local corners ascend with the builder's, so each group is in the builder's order.
        edges.sort_unstable();
        let mut mate = vec![NONE; n as usize];
        let position = |v: u32| self.position(v);
        let local_of = |corner: u32| {
            let t = (corner / 3) as u64;
            let i = self.faces.binary_search_by_key(&t, |f| f.triangle);
            3 * i.expect("a corner of the group") as u32 + corner % 3
        };
        let tri = |t: u32| {
            let i = self.faces.binary_search_by_key(&(t as u64), |f| f.triangle);
            self.faces[i.expect("a triangle of the group")].vertices
        };
        for run in edges.chunk_by(|x, y| x.0 == y.0) {
            let pairs = match run {
                [_] => continue,
                [x, y] => vec![(x.1, y.1)],
                _ => {
                    let lo = (run[0].0 >> 32) as u32;
                    let hi = run[0].0 as u32;
                    let group: Vec<(u32, u32)> =
                        run.iter().map(|x| (hi, self.corner(x.1))).collect();
                    let paired = pair_around_edge(&position, &tri, lo, &group);
                    paired
                        .into_iter()
                        .map(|(a, b)| (local_of(a), local_of(b)))
                        .collect()
                }
            };
            for (a, b) in pairs {
                mate[a as usize] = b;
                mate[b as usize] = a;
            }
        }
        self.mate = mate;
    }

    /// Flips the triangles the orientation round flips (`orient.rs`): `[a, b, c]` becomes
    /// `[a, c, b]`, corner `k` of a triangle becomes corner `2 - k`, its mates following, as
    /// the builder flips them.
    fn orient(&mut self, k: u32, flips: &Flips) -> Result<(), SplitError> {
        let (patch, parity) = local_patches(self)?;
        let flipped: Vec<bool> = (0..self.faces.len())
            .map(|i| flips.of(k, patch[i]) != (parity[i] == 1))
            .collect();
        if !flipped.contains(&true) {
            return Ok(());
        }
        let remap = |c: u32| match flipped[(c / 3) as usize] {
            true => c - c % 3 + (2 - c % 3),
            false => c,
        };
        let mut mate = vec![NONE; self.mate.len()];
        for (c, &m) in self.mate.iter().enumerate() {
            mate[remap(c as u32) as usize] = if m == NONE { NONE } else { remap(m) };
        }
        self.mate = mate;
        for (f, _) in self.faces.iter_mut().zip(&flipped).filter(|x| *x.1) {
            f.vertices.swap(1, 2);
        }
        let corners = 0..3 * self.faces.len() as u32;
        self.own_at = corners.map(|c| self.is_own(self.vertex(c))).collect();
        Ok(())
    }

    /// `(vertex, local corner)` of every corner at one of the cell's vertices, sorted: each
    /// vertex's corners in a run, ascending.
    fn corners_by_vertex(&self) -> Vec<(u32, u32)> {
        let corners = 0..3 * self.faces.len() as u32;
        let mut at: Vec<(u32, u32)> = corners
            .filter(|&c| self.own_at[c as usize])
            .map(|c| (self.vertex(c), c))
            .collect();
        at.sort_unstable();
        at
    }

    /// Step 2: the fans of the cell's vertices other than their first, in local corners.
    fn extra_fans(&self) -> Vec<Vec<u32>> {
        let mut out = Vec::new();
        let mut fan_of = vec![NONE; self.mate.len()];
        for run in self.corners_by_vertex().chunk_by(|a, b| a.0 == b.0) {
            let mut fans = 0u32;
            for &(_, c0) in run {
                if fan_of[c0 as usize] != NONE {
                    continue;
                }
                let mut fan = Vec::new();
                walk_fan(c0, &self.mate, |c| {
                    fan_of[c as usize] = fans;
                    fan.push(c);
                });
                if fans > 0 {
                    fan.sort_unstable();
                    out.push(fan);
                }
                fans += 1;
            }
        }
        out
    }
}

/// Round 1 of the cell tasks: the extra fans of cell `k`'s vertices (the copies the builder
/// makes there), for [`number_copies`]. Fails with [`SplitError::NotLocal`] when the cell
/// shows a repair it cannot make alone.
pub fn cell_fans(
    dir: &Path,
    manifest: &Manifest,
    k: u32,
    flips: &Flips,
) -> Result<Vec<ExtraFan>, SplitError> {
    let mut cell = Cell::read(dir, manifest, k)?;
    cell.orient(k, flips)?;
    let fans = cell.extra_fans();
    Ok(fans
        .into_iter()
        .map(|fan| {
            let corners: Vec<u32> = fan.iter().map(|&c| cell.corner(c)).collect();
            ExtraFan {
                first: corners[0],
                corners,
            }
        })
        .collect())
}

/// Round 2 of the cell tasks: cell `k`'s first piece written to `out` (a piece,
/// `formats/blocks.md`): the triangles it owns in triangle order, in the repaired mesh's
/// vertices (`copies` from [`number_copies`] over every cell's [`cell_fans`]), and the records
/// (position and quadric in the frame of the manifest's used bounding box, with
/// `boundary_weight` on the boundary planes) of its vertices with triangles. The records equal
/// the one-process `initial_quadrics` bit for bit.
pub fn cell_piece(
    dir: &Path,
    manifest: &Manifest,
    k: u32,
    (flips, copies): (&Flips, &Copies),
    boundary_weight: f64,
    out: &Path,
) -> Result<PieceCounts, SplitError> {
    let mut cell = Cell::read(dir, manifest, k)?;
    cell.orient(k, flips)?;
    let n = 3 * cell.faces.len() as u32;
    let mesh: Vec<u32> = (0..n)
        .map(|c| copies.of(cell.corner(c)).unwrap_or(cell.vertex(c)))
        .collect();
    check_multi_edges(&cell, &mesh)?;
    let origin = manifest
        .used_bounds
        .map_or(DVec3::ZERO, |b: BoundingBox| b.centre());
    let records = records(&cell, &mesh, origin, boundary_weight);
    let faces: Vec<[u32; 3]> = (0..cell.faces.len())
        .filter(|&i| cell.faces[i].owner == k)
        .map(|i| [0, 1, 2].map(|j| mesh[3 * i + j]))
        .collect();
    contents::write_piece(out, &faces, &records)?;
    Ok(PieceCounts {
        faces: faces.len() as u64,
        vertices: records.len() as u64,
    })
}

/// Step 4: the records of the cell's vertices (and copies) with triangles, ascending: the
/// position and the quadrics in the frame centred at `origin`, summed as `initial_quadrics`
/// sums them (face planes in triangle order, then the point regulariser, the boundary planes
/// apart).
fn records(cell: &Cell, mesh: &[u32], origin: DVec3, boundary_weight: f64) -> Vec<Record> {
    let at = |c: u32| cell.position(cell.vertex(c)) - origin;
    let own = |c: u32| cell.own_at[c as usize];
    let mut ids: Vec<(u32, u32)> = (0..mesh.len() as u32)
        .filter(|&c| own(c))
        .map(|c| (mesh[c as usize], c))
        .collect();
    ids.sort_unstable();
    ids.dedup_by_key(|x| x.0);
    let slot = |c: u32| {
        let v = mesh[c as usize];
        ids.binary_search_by_key(&v, |x| x.0)
            .expect("an own vertex")
    };
    let mut planes = vec![Quadric::default(); ids.len()];
    for i in 0..cell.faces.len() as u32 {
        let [a, b, c] = [3 * i, 3 * i + 1, 3 * i + 2];
        let Some(fq) = Quadric::of_triangle(at(a), at(b), at(c)) else {
            continue;
        };
        for x in [a, b, c].into_iter().filter(|&x| own(x)) {
            planes[slot(x)].add(&fq);
        }
    }
    for (q, &(_, c)) in planes.iter_mut().zip(&ids) {
        let scale = POINT_REGULARISATION * q.weight;
        q.add(&Quadric::from_point(at(c), scale));
    }
    let rims = rims(cell, mesh, &at, boundary_weight, &slot, ids.len());
    let record = |((&(v, c), planes), rim): ((&(u32, u32), Quadric), Option<Quadric>)| Record {
        vertex: v,
        position: at(c),
        quadric: VertexQuadric { planes, rim },
    };
    ids.iter().zip(planes).zip(rims).map(record).collect()
}

/// Step 3: refuses two distinct edges between the same two vertices (of which one is the
/// cell's) once the fans are split.
fn check_multi_edges(cell: &Cell, mesh: &[u32]) -> Result<(), SplitError> {
    let mut edges: Vec<(u64, u32)> = Vec::new();
    for c in 0..mesh.len() as u32 {
        if cell.own_at[c as usize] || cell.own_at[next_c(c) as usize] {
            let (a, b) = (mesh[c as usize], mesh[next_c(c) as usize]);
            edges.push(((a.min(b) as u64) << 32 | a.max(b) as u64, c));
        }
    }
    edges.sort_unstable();
    for run in edges.chunk_by(|x, y| x.0 == y.0) {
        let clean = match run {
            [_] => true,
            [x, y] => cell.mate[x.1 as usize] == y.1,
            _ => false,
        };
        if !clean {
            let c = run[1].1;
            return Err(SplitError::NotLocal {
                path: cell.face_path.clone(),
                offset: cell.at((c / 3) as usize),
                repair: GlobalRepair::MultiEdge,
                what: format!(
                    "{} half-edges join vertices {} and {} as distinct edges once the fans are \
                     split: the mesh builder detaches one end, in rounds over the whole mesh, \
                     which the streaming split does not do; build this scan in one process",
                    run.len(),
                    run[0].0 >> 32,
                    run[0].0 as u32
                ),
            });
        }
    }
    Ok(())
}

/// Step 4's boundary planes: for every boundary half-edge with an end in the cell, in corner
/// order, the plane through the edge perpendicular to its triangle, scaled by the squared
/// length and `weight`, added to each end of the cell (as `initial_quadrics` adds them).
fn rims(
    cell: &Cell,
    mesh: &[u32],
    at: &impl Fn(u32) -> DVec3,
    weight: f64,
    slot: &impl Fn(u32) -> usize,
    n: usize,
) -> Vec<Option<Quadric>> {
    let mut out: Vec<Option<Quadric>> = vec![None; n];
    if weight <= 0.0 {
        return out;
    }
    for c in 0..mesh.len() as u32 {
        let ends = [next_c(c), c];
        if cell.mate[c as usize] != NONE || !ends.iter().any(|&e| cell.own_at[e as usize]) {
            continue;
        }
        // The boundary half-edge runs from c's head to its tail; its face is c's.
        let (pa, pb) = (at(next_c(c)), at(c));
        let f = c / 3 * 3;
        let [fa, fb, fc] = [f, f + 1, f + 2].map(at);
        let face_normal = (fb - fa).cross(fc - fa).normalize_or_zero();
        let e = pb - pa;
        let n = e.cross(face_normal).normalize_or_zero();
        if n == DVec3::ZERO {
            continue;
        }
        let q = Quadric::from_plane(n, pa, weight * e.length_squared(), 0.0);
        for x in ends.into_iter().filter(|&x| cell.own_at[x as usize]) {
            out[slot(x)].get_or_insert_with(Quadric::default).add(&q);
        }
    }
    out
}

/// The cell tasks over every cell, on this process's threads: [`cell_fans`], the copies
/// numbered, then [`cell_piece`] into `out_dir/first.piece{k}`. Returns the pieces in cell
/// order and the copies; on error (a refusal of any cell voids them all) no piece is left.
pub fn cell_pieces(
    dir: &Path,
    boundary_weight: f64,
    out_dir: &Path,
) -> Result<(Vec<PathBuf>, Copies), SplitError> {
    let runner = crate::pm::partition::runner::RayonRunner;
    super::rounds::cell_pieces_by(dir, boundary_weight, out_dir, &runner)
}

/// [`cell_pieces`] on this process's threads without the round files: the rounds' answers
/// held in memory (what the runner's rounds are checked against).
#[cfg(test)]
pub(super) fn cell_pieces_in_memory(
    dir: &Path,
    boundary_weight: f64,
    out_dir: &Path,
) -> Result<(Vec<PathBuf>, Copies), SplitError> {
    use super::orient::{CellPatches, cell_patches, orient};
    use rayon::prelude::*;
    let manifest = Manifest::read(&dir.join("manifest"))?;
    let n = manifest.cells.len() as u32;
    let patches: Vec<CellPatches> = (0..n)
        .into_par_iter()
        .map(|k| cell_patches(dir, &manifest, k))
        .collect::<Result<_, _>>()?;
    let flips = orient(dir, &patches)?;
    drop(patches);
    let fans: Vec<Vec<ExtraFan>> = (0..n)
        .into_par_iter()
        .map(|k| cell_fans(dir, &manifest, k, &flips))
        .collect::<Result<_, _>>()?;
    let copies = number_copies(
        manifest.input_vertices,
        fans.into_iter().flatten().collect(),
    )?;
    let pieces: Vec<PathBuf> = (0..n)
        .map(|k| out_dir.join(format!("first.piece{k}")))
        .collect();
    let made = (0..n).into_par_iter().try_for_each(|k| {
        cell_piece(
            dir,
            &manifest,
            k,
            (&flips, &copies),
            boundary_weight,
            &pieces[k as usize],
        )
        .map(|_| ())
    });
    if let Err(e) = made {
        for p in &pieces {
            let _ = std::fs::remove_file(p);
        }
        return Err(e);
    }
    Ok((pieces, copies))
}
