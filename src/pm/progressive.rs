//! The progressive mesh: base mesh + ordered vertex splits, vertices in PM order, and a cursor
//! that walks the levels one split at a time.

use super::collapse::{half_edge_collapse, vertex_split};
use super::decimate::{Collapse, DecimateParams, FlatMesh, Stop, decimate_with_seams};
use super::partition::stream::{
    GlobalRepair, SplitError, assemble_from_cells, decimate_from_cells,
};
use super::partition::{InputPoints, first_cells};
use super::pins::{Pins, PinsError};
use super::seams::Seams;
use crate::mesh::{BoundingBox, CornerTable, Mesh, PolygonMesh, SlotIndex, SourceMap, VertexId};
use crate::progress::Progress;
use glam::DVec3;

// Rebuilding from stored parts (`.pyr` files) lives in its own file; a child module so that it
// can fill the private fields.
#[path = "parts.rs"]
mod parts;
pub use parts::PmParts;
pub use parts::SplitReplay;

/// Options for [`ProgressiveMesh::build`]. The build collapses greedily by quadric error until
/// a target is met, the error bound is exceeded, or no legal collapse is left.
#[derive(Clone, Debug, PartialEq)]
pub struct PmOptions {
    /// Stop when the mesh has at most this many (referenced) vertices. Default 0: as far as
    /// legal collapses go.
    pub target_vertices: usize,
    /// Stop when the mesh has at most this many faces. Default 0.
    pub target_faces: usize,
    /// Stop before the first collapse whose quadric error (an RMS distance to the original
    /// planes around the merged vertices) exceeds this fraction of the bounding-box diagonal.
    /// Default `None` (no error bound).
    pub max_error: Option<f64>,
    /// Largest rotation of any face normal a collapse may cause, in degrees, while at least 5 %
    /// of the input's faces are left. Default 45 (keeps creases at fine levels). Towards the
    /// coarse end the bound widens to the fold bound, about 75°, reached at 1 % of the faces
    /// (`docs/pm-legality.md`).
    pub max_normal_angle_degrees: f64,
    /// Triangle quality `4√3·A / Σl²` (1 = equilateral) below which a face is a sliver. A
    /// collapse that leaves a worse sliver around the removed vertex than there was pays a
    /// penalty on top of its quadric error (up to the error of moving the surface a tenth of an
    /// edge length), so fine levels stay well shaped and coarse levels may take the collapses
    /// through thin triangles that keep the shape. Default 0.05; 0 turns the penalty off.
    pub min_quality: f64,
    /// Largest valence a collapse may create. Default 32.
    pub max_valence: usize,
    /// Build the hierarchy in spatial blocks of at most this many vertices, their borders
    /// pinned, merged pairwise until one block holds the base (`docs/partitioned.md`). Default
    /// `None`: the whole mesh in one decimation. Not stored in `.pyr` files (the hierarchy
    /// itself is).
    pub block_vertices: Option<usize>,
    /// With `block_vertices`: run every pass of the partitioned build through task files in a
    /// new directory under this one, removed afterwards (`docs/partitioned.md`, "Running the
    /// passes through files"); the hierarchy is the same bit for bit. Default `None`: the passes
    /// run in memory.
    pub block_scratch: Option<std::path::PathBuf>,
    /// With `block_scratch`: what runs each round's tasks (`None`: this process's threads,
    /// [`crate::pm::blocks::RayonRunner`]). Any runner gives the same hierarchy.
    pub block_runner: Option<super::blocks::SharedRunner>,
    /// With `block_scratch`: the file the input was read from. An uncompressed PLY file is
    /// then split into cells in one pass and the cell tasks make the first pieces, instead of
    /// the whole working mesh (`docs/partitioned.md`, "Splitting a scan into cell files in one
    /// pass"); the hierarchy is the same bit for bit, and [`ProgressiveMesh::first_pieces`]
    /// says which way it went. Default `None`: from the whole mesh.
    pub block_input: Option<std::path::PathBuf>,
    /// Weight λ of the boundary constraint planes (each boundary edge adds a plane through it,
    /// perpendicular to its face, scaled by λ·|e|²) while at least 5 % of the input's faces are
    /// left; at the coarse end (1 %) they count 0.3 λ, so that hole rims give up the vertices the
    /// surface needs. Default 10 (`docs/algorithms.md` §4.3); 0 lets boundaries drift.
    pub boundary_weight: f64,
    /// Weight of texture-coordinate error against geometric error for an input with texture
    /// coordinates: a texture-coordinate error of `1 / uv_weight` costs as much as a distance
    /// of the bounding box's largest side (meshoptimizer's attribute weights use the same
    /// units). Default 0.25; 0 keeps the seams but ignores how the texture shifts
    /// (`docs/seams.md`).
    pub uv_weight: f64,
}

impl Default for PmOptions {
    fn default() -> Self {
        PmOptions {
            target_vertices: 0,
            target_faces: 0,
            max_error: None,
            max_normal_angle_degrees: 45.0,
            min_quality: 0.05,
            max_valence: 32,
            block_vertices: None,
            block_scratch: None,
            block_runner: None,
            block_input: None,
            boundary_weight: 10.0,
            uv_weight: 0.25,
        }
    }
}

/// Why a progressive mesh could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PmError {
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// The input polygons cannot be made into a mesh ([`ProgressiveMesh::from_polygons`]).
    #[error("cannot build the mesh: {0}")]
    Mesh(#[from] crate::mesh::BuildError),
    /// A broken internal invariant; please report.
    #[error("internal error in the progressive mesh (please report): {0}")]
    Internal(String),
    /// A task file of a partitioned build run through files
    /// ([`PmOptions::block_scratch`]) could not be written or read back.
    #[error("{0}")]
    BlockFile(#[from] super::BlockFileError),
}

/// One vertex split: the exact inverse of one half-edge collapse. Split `i` of a
/// [`ProgressiveMesh`] creates PM vertex `n_base + i`. All vertices are PM indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VertexSplit {
    /// The vertex the split creates (`u`, removed by the collapse). Its position is
    /// `original_positions()[vertex]`.
    pub vertex: u32,
    /// The survivor `v_s` (the collapse `u → v_s` keeps its position). Always `< vertex`.
    pub survivor: u32,
    /// `v_l`: apex of the face `(u, v_s, v_l)` the split re-creates; `None` when `u→v_s` was a
    /// boundary edge with no face on that side.
    pub left: Option<u32>,
    /// `v_r`: apex of the face `(v_s, u, v_r)`; `None` on the other boundary side.
    ///
    /// The fan that moves to `u` is identified by the wings: the faces around `v_s` from the
    /// edge `(v_s, v_l)` counter-clockwise to the edge `(v_s, v_r)` (or to the boundary).
    pub right: Option<u32>,
}

impl VertexSplit {
    /// Number of faces the split adds (1 or 2).
    pub(crate) fn n_new_faces(&self) -> usize {
        self.left.is_some() as usize + self.right.is_some() as usize
    }
}

/// A progressive mesh: vertices renumbered so that level `n` is the mesh on the first `n`
/// vertices, for `n_base_vertices() <= n <= n_vertices()`.
///
/// Unreferenced (isolated) vertices of the input take no part in the hierarchy: they get the
/// PM indices after `n_vertices()` (in input slot order), so [`pm_to_mesh`](Self::pm_to_mesh)
/// still covers every input vertex and the finest level plus those vertices maps back onto the
/// user's file. Copies made by the mesh builder's repairs are ordinary vertices here; the
/// builder's `SourceMap` maps them back.
#[derive(Clone, Debug)]
pub struct ProgressiveMesh {
    n_base: usize,
    positions: Vec<DVec3>,
    pm_to_mesh: Vec<u32>,
    mesh_to_pm: Vec<u32>,
    splits: Vec<VertexSplit>,
    /// Finest-level faces in PM indices, in the input mesh's face slot order.
    faces: Vec<[u32; 3]>,
    /// Faces at the base level.
    n_base_faces: usize,
    /// Quadric error (RMS distance) of each split's collapse.
    errors: Vec<f32>,
    /// Why the build stopped at the base level; `None` for a hierarchy loaded from parts.
    stop: Option<Stop>,
    /// Whether every collapse kept the input's texture seams (`super::seams`), so that each
    /// level's corners follow from the finest ones (`super::level_corners`).
    keeps_seams: bool,
    /// Per pass of a partitioned build, the vertices it pinned (`super::pins`); `None` for a
    /// hierarchy built in one piece or one whose passes pinned nothing.
    pins: Option<Pins>,
    /// How a partitioned build through files made its first pieces; `None` otherwise.
    first_pieces: Option<FirstPieces>,
}

/// How a partitioned build through files ([`PmOptions::block_scratch`]) made the pieces its
/// first pass starts from; either way gives the same hierarchy.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FirstPieces {
    /// The input file split into cells in one pass, one cell task per cell
    /// ([`PmOptions::block_input`]).
    Cells,
    /// The whole working mesh in memory, and why not the cells.
    WholeMesh(String),
}

impl std::fmt::Display for FirstPieces {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FirstPieces::Cells => write!(f, "first pieces split from the file into cells"),
            FirstPieces::WholeMesh(why) => {
                write!(f, "first pieces made from the whole mesh ({why})")
            }
        }
    }
}

/// A corner table's vertex list as triangles, reusing its allocation when its capacity is a
/// whole number of triangles (else copied).
pub(crate) fn triangles_of(corner_vertex: Vec<u32>) -> Vec<[u32; 3]> {
    match bytemuck::allocation::try_cast_vec(corner_vertex) {
        Ok(triangles) => triangles,
        Err((_, corner_vertex)) => corner_vertex
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
    }
}

const NONE: u32 = u32::MAX;

impl ProgressiveMesh {
    /// Builds the hierarchy by greedy quadric-error half-edge collapses on a copy of `mesh`
    /// (which must satisfy [`Mesh::validate`]; the builder's output does).
    pub fn build(
        mesh: &Mesh,
        opts: &PmOptions,
        progress: &dyn Progress,
    ) -> Result<ProgressiveMesh, PmError> {
        let params = decimate_params(opts, mesh.bbox_diagonal())?;
        let n_slots = mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0);
        let mut positions = vec![DVec3::ZERO; n_slots];
        for v in mesh.vertices() {
            positions[v.slot()] = mesh.position(v);
        }
        // The mesh is its own input: its slots are the input's vertices.
        let points = InputPoints {
            positions: &positions,
            polygons: mesh.n_faces() as u64,
            source: None,
        };
        let flat = FlatMesh::from_mesh(mesh);
        let decimated = decimate_flat(flat, &params, opts, (None, &points), progress)?;
        let isolated: Vec<u32> = mesh
            .vertices()
            .filter(|&v| mesh.is_isolated(v))
            .map(|v| v.slot() as u32)
            .collect();
        let faces = |mesh_to_pm: &[u32]| {
            mesh.faces()
                .map(|f| mesh.face_vertices(f).map(|v| mesh_to_pm[v.slot()]))
                .collect()
        };
        let position = |v: u32| positions[v as usize];
        Self::from_decimation(
            decimated,
            (n_slots, mesh.n_vertices()),
            &isolated,
            position,
            faces,
        )
    }

    /// The hierarchy of `input` after the mesh builder's repairs ([`Mesh::from_polygons`]),
    /// with the map from its vertices back onto `input`'s: the same hierarchy as
    /// [`Self::build`] on the built mesh, without ever making the half-edge mesh (whose
    /// records take several times the memory of the hierarchy itself).
    pub fn from_polygons(
        input: &PolygonMesh,
        opts: &PmOptions,
        progress: &dyn Progress,
    ) -> Result<(ProgressiveMesh, SourceMap), PmError> {
        let why = match cells_input(opts) {
            Err(why) => why,
            Ok(path) => match decimate_from_cells(path, opts, progress) {
                Ok(passed) => {
                    let (mut pm, source) = assemble_from_cells(input, passed)?;
                    pm.first_pieces = Some(FirstPieces::Cells);
                    return Ok((pm, source));
                }
                Err(SplitError::Build(e)) => return Err(e),
                Err(SplitError::File(e)) => return Err(e.into()),
                Err(SplitError::NotLocal { repair, .. }) => not_local(repair),
                Err(e @ SplitError::Read(_)) => e.to_string(),
            },
        };
        let repaired = CornerTable::from_polygons(input)?;
        let mut pm = Self::from_corners(input, repaired.corners, &repaired.source, opts, progress)?;
        if opts.block_vertices.is_some() && opts.block_scratch.is_some() {
            pm.first_pieces = Some(FirstPieces::WholeMesh(why));
        }
        Ok((pm, repaired.source))
    }

    /// How a partitioned build through files made its first pieces (`None` for any other
    /// build, and for a hierarchy read from a file).
    pub fn first_pieces(&self) -> Option<&FirstPieces> {
        self.first_pieces.as_ref()
    }

    /// [`Self::from_polygons`] on the builder's corner table of `input`.
    pub(crate) fn from_corners(
        input: &PolygonMesh,
        corners: CornerTable,
        source: &SourceMap,
        opts: &PmOptions,
        progress: &dyn Progress,
    ) -> Result<ProgressiveMesh, PmError> {
        let face_source = &source.face_source;
        let source = &source.vertex_source;
        let positions: Vec<DVec3> = source
            .iter()
            .map(|&s| input.positions[s as usize])
            .collect();
        let diagonal = BoundingBox::of(positions.iter().copied()).map_or(0.0, |b| b.diagonal());
        let params = decimate_params(opts, diagonal)?;
        // Vertex slot `i` is vertex `i` and face slot `t` triangle `t` (`CornerTable` docs).
        let mut referenced = vec![false; source.len()];
        for &v in &corners.corner_vertex {
            referenced[v as usize] = true;
        }
        let isolated: Vec<u32> = (0..source.len() as u32)
            .filter(|&v| !referenced[v as usize])
            .collect();
        drop(referenced);
        // The working mesh copies the table; of the table only the corners' vertices are read
        // again (they become the finest faces, in place), so the twins go before the
        // decimation's peak.
        let extent = BoundingBox::of(positions.iter().copied()).map_or(0.0, |b| b.max_side());
        let flat = FlatMesh::from_corners(positions, &corners);
        // A partitioned build through task files decides its collapses in blocks whose files
        // do not carry the seams (formats/blocks.md).
        let seams = match (opts.block_vertices, &opts.block_scratch) {
            (Some(_), Some(_)) => None,
            _ => Seams::of(
                input,
                &corners.corner_vertex,
                face_source,
                source,
                &flat,
                opts.uv_weight,
                extent,
            ),
        };
        let CornerTable {
            mut corner_vertex, ..
        } = corners;
        let keeps_seams = seams.is_some();
        let points = InputPoints {
            positions: &input.positions,
            polygons: input.n_faces() as u64,
            source: Some(source),
        };
        let decimated = decimate_flat(flat, &params, opts, (seams, &points), progress)?;
        let faces = move |mesh_to_pm: &[u32]| {
            for v in &mut corner_vertex {
                *v = mesh_to_pm[*v as usize];
            }
            triangles_of(corner_vertex)
        };
        let position = |v: u32| input.positions[source[v as usize] as usize];
        let mut pm = Self::from_decimation(
            decimated,
            (source.len(), source.len()),
            &isolated,
            position,
            faces,
        )?;
        pm.keeps_seams = keeps_seams;
        Ok(pm)
    }

    /// Puts a decimation of a mesh with `n_vertices` vertices in slots `0..n_slots` into PM
    /// order: surviving referenced vertices (slot order), removed vertices in reverse collapse
    /// order, then the `isolated` vertices (slot order). `position` gives each slot's original
    /// position (the working mesh holds them recentred), `faces` the finest faces in face slot
    /// order, their vertices mapped by the slot → PM index map it is given.
    pub(crate) fn from_decimation(
        decimated: Decimated,
        (n_slots, n_vertices): (usize, usize),
        isolated: &[u32],
        position: impl Fn(u32) -> DVec3,
        faces: impl FnOnce(&[u32]) -> Vec<[u32; 3]>,
    ) -> Result<ProgressiveMesh, PmError> {
        let Decimated {
            collapses,
            survivors,
            n_base_faces,
            stop,
            passes,
        } = decimated;
        let mut mesh_to_pm = vec![NONE; n_slots];
        let mut pm_to_mesh: Vec<u32> = Vec::with_capacity(n_vertices);
        for v in survivors {
            mesh_to_pm[v as usize] = pm_to_mesh.len() as u32;
            pm_to_mesh.push(v);
        }
        let n_base = pm_to_mesh.len();
        for c in collapses.iter().rev() {
            mesh_to_pm[c.from as usize] = pm_to_mesh.len() as u32;
            pm_to_mesh.push(c.from);
        }
        for &v in isolated {
            mesh_to_pm[v as usize] = pm_to_mesh.len() as u32;
            pm_to_mesh.push(v);
        }
        if pm_to_mesh.len() != n_vertices {
            return Err(PmError::Internal("vertex permutation is incomplete".into()));
        }
        let map = |s: u32| {
            if s == NONE {
                None
            } else {
                Some(mesh_to_pm[s as usize])
            }
        };
        let splits: Vec<VertexSplit> = collapses
            .iter()
            .rev()
            .map(|c| VertexSplit {
                vertex: mesh_to_pm[c.from as usize],
                survivor: mesh_to_pm[c.to as usize],
                left: map(c.left),
                right: map(c.right),
            })
            .collect();
        let errors = collapses
            .iter()
            .rev()
            .map(|c| c.error_sq.sqrt() as f32)
            .collect();
        drop(collapses);
        let pins = pins_in_split_order(passes, &mesh_to_pm);
        let positions = pm_to_mesh.iter().map(|&v| position(v)).collect();
        let faces = faces(&mesh_to_pm);
        Ok(ProgressiveMesh {
            n_base,
            positions,
            pm_to_mesh,
            mesh_to_pm,
            splits,
            faces,
            n_base_faces,
            errors,
            stop: Some(stop),
            keeps_seams: false,
            pins,
            first_pieces: None,
        })
    }

    /// Number of vertices at the coarsest level, `n0`.
    pub fn n_base_vertices(&self) -> usize {
        self.n_base
    }

    /// Number of vertices at the finest level (all vertices referenced by a face).
    pub fn n_vertices(&self) -> usize {
        self.n_base + self.splits.len()
    }

    /// Why the build stopped at the base level (the target, or no legal collapse left and
    /// which rules refused); `None` for a hierarchy loaded from a file.
    pub fn stop(&self) -> Option<&Stop> {
        self.stop.as_ref()
    }

    /// Whether the hierarchy keeps the input's texture seams: built from a textured input
    /// (per-corner data or several materials) in one piece, every collapse obeying the seam
    /// rule (`docs/seams.md`), so that every level has the input's per-corner data
    /// ([`crate::pm::level_corners`]).
    pub fn keeps_seams(&self) -> bool {
        self.keeps_seams
    }

    /// Marks a hierarchy read from a file as keeping the seams (the file says so; the level
    /// replay checks it).
    pub(crate) fn set_keeps_seams(&mut self, keeps: bool) {
        self.keeps_seams = keeps;
    }

    /// One phrase describing the base level against the floor of its topology, and why the
    /// build stopped there when known: "base level 4 vertices, 4 triangles; topology floor 4
    /// vertices (1 component, 0 holes, genus 0); no legal collapse left (valence-3 wing: 6
    /// edges)".
    pub fn describe_base(&self) -> String {
        let base = self.base_mesh();
        let mut s = format!(
            "base level {} vertices, {} triangles; topology floor {}",
            self.n_base,
            base.n_faces(),
            base.topology().describe_floor()
        );
        if let Some(stop) = &self.stop {
            s += &format!("; {stop}");
        }
        s
    }

    /// The vertices a partitioned build pinned, per pass (PM indices): the detail pyramid
    /// leaves a split's ring vertices pinned in its pass untouched. `None` for a hierarchy
    /// built in one piece (or whose passes pinned nothing).
    pub fn pins(&self) -> Option<&Pins> {
        self.pins.as_ref()
    }

    /// Gives the hierarchy the pin record `pins` (read from a file), after checking it
    /// against the splits; an empty record is none.
    pub fn set_pins(&mut self, pins: Option<Pins>) -> Result<(), PinsError> {
        if let Some(p) = &pins {
            p.check(self.n_base, self.splits.len(), |k| self.splits[k].survivor)?;
        }
        self.pins = pins.filter(|p| !p.is_empty());
        Ok(())
    }

    /// Number of faces at the coarsest level.
    pub fn n_base_faces(&self) -> usize {
        self.n_base_faces
    }

    /// Number of faces at the finest level.
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// The vertex splits; split `i` creates PM vertex `n_base_vertices() + i`.
    pub fn splits(&self) -> &[VertexSplit] {
        &self.splits
    }

    /// Quadric error of each split's collapse (an RMS distance in model units), by split index.
    pub fn split_errors(&self) -> &[f32] {
        &self.errors
    }

    /// Original positions in PM order (isolated input vertices at the end, after
    /// `n_vertices()`).
    pub fn original_positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// PM index → vertex slot in the input [`Mesh`] (covers every input vertex).
    pub fn pm_to_mesh(&self) -> &[u32] {
        &self.pm_to_mesh
    }

    /// Input vertex slot → PM index (`u32::MAX` for slots the input mesh did not use).
    pub fn mesh_to_pm(&self) -> &[u32] {
        &self.mesh_to_pm
    }

    /// The finest-level faces in PM indices, in the input mesh's face order, each starting at
    /// the same corner as in the input.
    pub fn finest_faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Number of faces at level `n` (clamped to the valid range).
    pub fn n_faces_at(&self, n: usize) -> usize {
        let n = n.clamp(self.n_base, self.n_vertices());
        self.n_base_faces
            + self.splits[..n - self.n_base]
                .iter()
                .map(|s| s.n_new_faces())
                .sum::<usize>()
    }

    /// The finest level with at most `faces` faces (the base level if even that has more):
    /// the most detailed level that fits a display budget.
    pub fn level_for_faces(&self, faces: usize) -> usize {
        let mut count = self.n_base_faces;
        let mut level = self.n_base;
        for s in &self.splits {
            count += s.n_new_faces();
            if count > faces {
                break;
            }
            level += 1;
        }
        level
    }

    /// The triangles of level `n` (clamped to the valid range) in PM indices `0..n`, in the
    /// order of the finest level's faces. A half-edge collapse `u → v` replaces `u` by `v` and
    /// deletes exactly the faces holding both, so mapping every finest vertex to its ancestor
    /// at level `n` and dropping degenerate triangles gives the level.
    pub fn level_triangles(&self, n: usize) -> Vec<[u32; 3]> {
        let n = n.clamp(self.n_base, self.n_vertices());
        let total = self.n_vertices();
        let mut ancestor: Vec<u32> = (0..total as u32).collect();
        for x in n..total {
            let s = self.splits[x - self.n_base].survivor as usize;
            ancestor[x] = ancestor[s];
        }
        self.faces
            .iter()
            .map(|t| t.map(|x| ancestor[x as usize]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect()
    }

    /// The compacted mesh at level `n`: vertex slot `i` is PM vertex `i`.
    pub(crate) fn level_mesh(&self, n: usize) -> Mesh {
        let n = n.clamp(self.n_base, self.n_vertices());
        let tris = self.level_triangles(n);
        mesh_from_clean(&self.positions[..n], &tris)
    }

    /// The base mesh (level `n_base_vertices()`): vertex slot `i` is PM vertex `i`.
    pub fn base_mesh(&self) -> Mesh {
        self.level_mesh(self.n_base)
    }

    /// A cursor at the finest level.
    pub fn cursor(&self) -> PmCursor<'_> {
        let n = self.n_vertices();
        let mesh = mesh_from_clean(&self.positions[..n], &self.faces);
        let handles: Vec<VertexId> = mesh.vertices().collect();
        PmCursor {
            pm: self,
            mesh,
            handles,
            level: n,
        }
    }
}

/// Builds a mesh from triangles that came out of a valid half-edge mesh (no repairs happen, so
/// vertex slot `i` is vertex `i`).
fn mesh_from_clean(positions: &[DVec3], tris: &[[u32; 3]]) -> Mesh {
    match Mesh::from_triangles(positions, tris) {
        Ok(b) => {
            debug_assert!(!b.report.repaired_anything() && b.mesh.n_vertices() == positions.len());
            b.mesh
        }
        // Positions are finite and indices in range by construction.
        Err(_) => Mesh::new(),
    }
}

/// Walks a [`ProgressiveMesh`] one vertex split at a time.
///
/// Invariant: vertex slot `i` of [`mesh`](Self::mesh) is PM vertex `i` for every live vertex
/// (`0..level()`). Moves in stack order (collapse undoes the last split, split redoes it) are
/// exact: the mesh records, including face and half-edge slots, are restored bit for bit.
pub struct PmCursor<'a> {
    pm: &'a ProgressiveMesh,
    mesh: Mesh,
    handles: Vec<VertexId>,
    level: usize,
}

impl PmCursor<'_> {
    /// The current number of vertices.
    pub fn level(&self) -> usize {
        self.level
    }

    /// The mesh at the current level (vertex slot == PM index).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Handle of PM vertex `i` (`i < level()`).
    pub fn vertex(&self, i: usize) -> VertexId {
        self.handles[i]
    }

    /// One level down: undoes the last split. False at the base level.
    pub fn collapse(&mut self) -> bool {
        if self.level <= self.pm.n_base {
            return false;
        }
        let s = self.pm.splits[self.level - 1 - self.pm.n_base];
        let u = self.handles[s.vertex as usize];
        let v = self.handles[s.survivor as usize];
        let Some(h) = self.mesh.find_halfedge(u, v) else {
            debug_assert!(false, "split record does not match the cursor mesh");
            return false;
        };
        let topo = half_edge_collapse(&mut self.mesh, h);
        debug_assert_eq!(topo.left.map(|x| x.slot() as u32), s.left);
        debug_assert_eq!(topo.right.map(|x| x.slot() as u32), s.right);
        self.level -= 1;
        true
    }

    /// One level up: applies the next split. False at the finest level.
    pub fn split(&mut self) -> bool {
        if self.level >= self.pm.n_vertices() {
            return false;
        }
        let s = self.pm.splits[self.level - self.pm.n_base];
        let h = |x: u32| self.handles[x as usize];
        let (v, l, r) = (h(s.survivor), s.left.map(h), s.right.map(h));
        match vertex_split(&mut self.mesh, v, l, r, self.pm.positions[self.level]) {
            Ok(u) => {
                debug_assert_eq!(u.slot(), self.level);
                self.handles[self.level] = u;
                self.level += 1;
                true
            }
            Err(_) => {
                debug_assert!(false, "split record does not match the cursor mesh");
                false
            }
        }
    }

    /// Moves to `level` (clamped to the valid range) one split at a time.
    pub fn seek(&mut self, level: usize) {
        let level = level.clamp(self.pm.n_base, self.pm.n_vertices());
        while self.level > level && self.collapse() {}
        while self.level < level && self.split() {}
    }

    /// Moves to the finest level with at most `faces` faces.
    pub(crate) fn seek_faces(&mut self, faces: usize) {
        let level = self.pm.level_for_faces(faces);
        self.seek(level);
    }
}

/// The input file a build from cells splits (`opts` asks for blocks through files and names
/// an uncompressed PLY file), or why there is none.
fn cells_input(opts: &PmOptions) -> Result<&std::path::Path, String> {
    let (Some(_), Some(_)) = (opts.block_vertices, &opts.block_scratch) else {
        return Err("not built in blocks through files".into());
    };
    let Some(path) = &opts.block_input else {
        return Err("no input file given".into());
    };
    let ply = crate::io::MeshFormat::from_path(path).is_ok_and(|f| f == crate::io::MeshFormat::Ply);
    match (ply, crate::io::is_gzip(path)) {
        (true, false) => Ok(path),
        (true, true) => Err("the file is compressed; the split reads an uncompressed PLY".into()),
        (false, _) => Err("the split reads PLY files only".into()),
    }
}

/// Why a build from cells gave way to the whole mesh when a cell refused `repair`.
fn not_local(repair: GlobalRepair) -> String {
    let what = match repair {
        GlobalRepair::Orientation => "a component that cannot be oriented",
        GlobalRepair::MultiEdge => "a multi-edge to detach",
    };
    format!("the scan has {what}, a repair the cells cannot make alone")
}

/// What a decimation of the whole mesh leaves: its collapses in order (vertex slots), the
/// surviving vertices in slot order, the base level's face count, why it stopped, and for a
/// partitioned build its passes in order: how many of the collapses each made and the vertex
/// slots it pinned (empty for a build in one piece).
pub(crate) struct Decimated {
    pub collapses: Vec<Collapse>,
    pub survivors: Vec<u32>,
    pub n_base_faces: usize,
    pub stop: Stop,
    pub passes: Vec<(usize, Vec<u32>)>,
}

/// The pin record of a partitioned build's `passes` (collapse order, vertex slots) in split
/// order and PM indices; `None` when nothing was pinned. Splits run in reverse collapse
/// order, so the passes do too.
fn pins_in_split_order(passes: Vec<(usize, Vec<u32>)>, mesh_to_pm: &[u32]) -> Option<Pins> {
    let pins = Pins::from_passes(passes.into_iter().rev().map(|(n, slots)| {
        let pm: Vec<u32> = slots.iter().map(|&v| mesh_to_pm[v as usize]).collect();
        (n, pm)
    }));
    (!pins.is_empty()).then_some(pins)
}

/// Decimates the working mesh in one piece, or in blocks when `opts` asks for them, the first
/// pass's cells cut from `input` as the streaming split cuts them.
fn decimate_flat(
    flat: FlatMesh,
    params: &DecimateParams,
    opts: &PmOptions,
    (mut seams, input): (Option<Seams>, &InputPoints),
    progress: &dyn Progress,
) -> Result<Decimated, PmError> {
    if let Some(max) = opts.block_vertices {
        let first = first_cells(input, flat.n_vertex_slots(), max);
        if let Some(scratch) = &opts.block_scratch {
            let runner = opts.block_runner.as_ref().map_or(
                &super::blocks::RayonRunner as &dyn super::blocks::TaskRunner,
                |r| &*r.0,
            );
            return super::partition::decimate_through_files(
                flat,
                params,
                (max, first),
                scratch,
                runner,
                progress,
            );
        }
        return super::partition::decimate_in_blocks(flat, params, max, (seams, first), progress);
    }
    let (collapses, coarse, outcome) = decimate_with_seams(flat, params, seams.as_mut(), progress);
    Ok(Decimated {
        collapses,
        survivors: coarse.survivors(),
        n_base_faces: coarse.n_faces(),
        stop: outcome.stop,
        passes: Vec::new(),
    })
}

/// Whether a hierarchy of `input` keeps texture seams: it has per-corner data or more than one
/// material (`docs/seams.md`). A partitioned build ([`PmOptions::block_vertices`]) keeps them
/// in memory; run through task files ([`PmOptions::block_scratch`]) it does not.
pub fn keeps_texture_seams(input: &PolygonMesh) -> bool {
    super::seams::is_textured(input)
}

/// The smallest block a partitioned build accepts: a block must have room for an interior
/// beside its border.
pub const MIN_BLOCK_VERTICES: usize = 16;

/// Checks `opts` and turns them into the decimator's parameters (the error bound relative to
/// `bbox_diagonal`).
pub(crate) fn decimate_params(
    opts: &PmOptions,
    bbox_diagonal: f64,
) -> Result<DecimateParams, PmError> {
    let angle = opts.max_normal_angle_degrees;
    if !(angle > 0.0 && angle <= 180.0) {
        return Err(PmError::InvalidOption(format!(
            "max normal angle must be in (0, 180] degrees, got {angle}"
        )));
    }
    if !(opts.min_quality >= 0.0 && opts.min_quality < 1.0) {
        return Err(PmError::InvalidOption(format!(
            "min quality must be in [0, 1), got {}",
            opts.min_quality
        )));
    }
    if !(opts.boundary_weight >= 0.0 && opts.boundary_weight.is_finite()) {
        return Err(PmError::InvalidOption(
            "boundary weight must be finite and >= 0".into(),
        ));
    }
    if !(opts.uv_weight >= 0.0 && opts.uv_weight.is_finite()) {
        return Err(PmError::InvalidOption(
            "uv weight must be finite and >= 0".into(),
        ));
    }
    if opts.block_vertices.is_some_and(|n| n < MIN_BLOCK_VERTICES) {
        return Err(PmError::InvalidOption(format!(
            "block vertices must be at least {MIN_BLOCK_VERTICES}"
        )));
    }
    if opts.max_valence < 3 {
        return Err(PmError::InvalidOption(
            "max valence must be at least 3".into(),
        ));
    }
    let max_error_sq = match opts.max_error {
        None => f64::INFINITY,
        Some(e) if e >= 0.0 && e.is_finite() => {
            let d = e * bbox_diagonal;
            d * d
        }
        Some(e) => {
            return Err(PmError::InvalidOption(format!(
                "max error must be >= 0, got {e}"
            )));
        }
    };
    let params = DecimateParams {
        target_vertices: opts.target_vertices,
        target_faces: opts.target_faces,
        max_error_sq,
        legality: super::Legality {
            max_valence: opts.max_valence,
            min_normal_cos: angle.to_radians().cos(),
            min_quality: opts.min_quality,
        },
        boundary_weight: opts.boundary_weight,
    };
    Ok(params)
}
