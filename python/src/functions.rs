//! The free functions over `(V, F)`: files, counts, simplification, subdivision, comparison.

use crate::arrays::{self, index_array, mesh_arrays, positions_array, triangles_array};
use crate::corners::corners_dict;
use crate::errors::{input_error, io_error, value_error};
use meshpyr::MeshInfo;
use meshpyr::choice::Choice;
use meshpyr::mesh::{Mesh, ScalarType};
use meshpyr::metrics::{FieldPercentiles, Reference, vertex_distances};
use meshpyr::pm::{PmOptions, SimplifyGoal, simplify_to_goal};
use meshpyr::subdiv::{self, Refinement, Scheme, SolverChoice, SubdivSettings};
use meshpyr::{NoProgress, PolygonMesh};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;

/// `(V, F)` of a mesh: float64 (n, 3) and int64 (m, 3).
pub(crate) type MeshPair<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

/// The arrays of a file-level mesh.
pub(crate) fn mesh_pair<'py>(py: Python<'py>, mesh: &PolygonMesh) -> MeshPair<'py> {
    let (v, f) = mesh_arrays(mesh);
    (positions_array(py, &v), triangles_array(py, &f))
}

/// A serialisable value as a Python dict, through JSON (the same keys and values as the
/// command line's `--json`).
pub(crate) fn to_dict<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyDict>> {
    let text = serde_json::to_string(value).map_err(input_error)?;
    let parsed = py.import("json")?.call_method1("loads", (text,))?;
    Ok(parsed.cast_into::<PyDict>()?)
}

/// Reads a mesh file (.obj, .ply, .off, .stl, each optionally gzipped as .gz) as ``(V, F)``:
/// V float64 (n, 3), F int64 (m, 3). Polygons are fan-triangulated from their first corner,
/// as meshpyr's mesh builder does, so ``(V, F)`` gives the same results as the file itself.
/// Vertices that no face uses are kept.
///
/// ``corners=True`` returns ``(V, F, C)``: C is a dict of what a textured scan holds per
/// triangle of F, with the keys present in the file: ``texcoord`` (m, 3, 2) and ``normal``
/// (m, 3, 3) per corner (NaN where a corner has none; float32 when the file stores float32),
/// ``material`` (m,) indices into ``materials`` (dicts with ``name`` and ``texture``) with
/// ``material_libraries`` and ``folder``, ``group`` (m,) indices into ``groups``. ``write``,
/// ``info`` and ``simplify`` take it back; filters and edits keep F, so it stays valid for
/// their results.
///
/// Raises OSError (FileNotFoundError, PermissionError, ...) when the file cannot be read,
/// FormatError when its content is damaged, ValueError for an unknown extension.
#[pyfunction]
#[pyo3(signature = (path, *, corners = false))]
pub(crate) fn read(py: Python<'_>, path: PathBuf, corners: bool) -> PyResult<Bound<'_, PyTuple>> {
    let mesh = py.detach(|| meshpyr::read_mesh(&path)).map_err(io_error)?;
    let (v, f) = mesh_pair(py, &mesh);
    if corners {
        let c = corners_dict(py, &mesh)?;
        PyTuple::new(py, [v.into_any(), f.into_any(), c.into_any()])
    } else {
        PyTuple::new(py, [v.into_any(), f.into_any()])
    }
}

/// `(V, F)` and an optional corners dict as a mesh.
pub(crate) fn mesh_with_corners(
    v: &Bound<'_, PyAny>,
    f: &Bound<'_, PyAny>,
    corners: Option<&Bound<'_, PyAny>>,
) -> PyResult<PolygonMesh> {
    let mut mesh = arrays::mesh(v, f)?;
    if let Some(c) = corners {
        crate::corners::apply(&mut mesh, c)?;
    }
    Ok(mesh)
}

/// Writes ``(V, F)`` to a mesh file; the extension chooses the format (.obj, .ply, .off, .stl,
/// optionally followed by .gz). PLY is binary with double positions; OBJ and OFF hold every
/// float64 exactly; STL holds float32 only. The file is replaced atomically: it appears complete or not at all.
///
/// ``corners`` (the dict of ``read(path, corners=True)``) adds texture coordinates, corner
/// normals, materials and groups: an OBJ gets ``vt``/``vn`` per corner, ``mtllib`` and
/// ``usemtl``, a PLY a per-face ``texcoord`` list, ``texnumber`` and ``TextureFile`` comments.
/// Relative material and image paths are rewritten to reach the same files from the new folder.
/// ``before`` (float64 (n, 3)) gives the positions the corners' normals were stored for (the
/// input's V after a filter or edit): the normals around vertices that moved are recomputed from
/// V, hard edges kept, as the command line does; without it they are written as given.
///
/// Raises ValueError for bad arrays or an unknown extension, OSError when the file cannot be
/// written.
#[pyfunction]
#[pyo3(signature = (path, v, f, /, corners = None, *, before = None))]
pub(crate) fn write(
    py: Python<'_>,
    path: PathBuf,
    v: &Bound<'_, PyAny>,
    f: &Bound<'_, PyAny>,
    corners: Option<&Bound<'_, PyAny>>,
    before: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let mut mesh = mesh_with_corners(v, f, corners)?;
    if let Some(before) = before {
        let before = arrays::vertices(before)?;
        if before.len() != mesh.n_vertices() {
            return Err(value_error(format!(
                "before has {} rows, V has {}: it must be the positions of the same vertices",
                before.len(),
                mesh.n_vertices()
            )));
        }
        mesh.refresh_normals(&before);
    }
    // The arrays are float64: PLY stores doubles and text formats print every float64 exactly,
    // whatever the values (else coordinates that happen to be float32 values would make a
    // float PLY, and commands reading it would write float32 results).
    mesh.position_type = Some(ScalarType::F64);
    py.detach(|| meshpyr::write_mesh(&path, &mesh))
        .map_err(io_error)
}

/// Counts, topology and size of ``(V, F)``, as a dict with the keys of ``meshpyr info
/// --json``: vertices, faces, polygons, edges, boundary_loops, components,
/// euler_characteristic, genus (None when not manifold), floor_vertices (the fewest vertices
/// its topology can be simplified to), pm_base (None), manifold, bbox_diagonal,
/// mean_edge_length, repairs (a dict of what the mesh builder would change to process it),
/// vertex_attributes and face_attributes, texture (None without ``corners``: texture
/// coordinates, seams, materials and images found or missing with the dict of
/// ``read(path, corners=True)``).
#[pyfunction]
#[pyo3(signature = (v, f, /, corners = None))]
pub(crate) fn info<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    corners: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = mesh_with_corners(v, f, corners)?;
    let info = py.detach(|| MeshInfo::of(&mesh)).map_err(input_error)?;
    to_dict(py, &info)
}

/// Quadric-error simplification by half-edge collapses, as ``meshpyr simplify``; give exactly
/// one target: ``faces`` (at most this many triangles), ``ratio`` (at most this fraction of
/// the triangles, in (0, 1]) or ``error`` (collapse while the quadric error, an RMS distance,
/// stays below this fraction of the bounding-box diagonal). ``prune`` first drops the connected
/// pieces whose bounding-box diagonal is below this fraction of the whole mesh's (a ratio still
/// refers to the input's triangles).
///
/// Returns ``(V2, F2, vertex_map)``: the kept vertices keep their positions, and
/// ``vertex_map[i]`` is the index in V of vertex i of V2 (so ``V2 == V[vertex_map]``).
/// When the topology allows no more collapses before the target, the result stops there and
/// a UserWarning says where and why.
///
/// ``max_angle`` is the largest rotation of a face normal one collapse may cause (degrees)
/// while at least 5 % of the faces are left (it widens to about 75° at 1 %), ``min_quality``
/// the triangle quality (4√3·area / Σ edge², 1 = equilateral) below which a collapse that
/// leaves a worse sliver pays a penalty, ``boundary_weight`` the weight of the planes that keep
/// boundaries in place (0 lets them drift; it falls to 0.3 of this towards 1 % of the faces).
///
/// ``corners`` (the dict of ``read(path, corners=True)``) makes the simplification keep the
/// texture: a vertex on a seam or material border collapses only along it, and each kept
/// corner takes its vertex's value on the same side of every seam. ``uv_weight`` weighs the
/// texture shift against distance (a texture error of ``1 / uv_weight`` costs as much as a
/// distance of the bounding box's largest side; 0 keeps the seams and ignores the shift). The
/// result is then ``(V2, F2, vertex_map, C2)``, C2 the corners dict of the output.
#[pyfunction]
#[pyo3(signature = (v, f, /, *, faces=None, ratio=None, error=None, prune=None, max_angle=PmOptions::default().max_normal_angle_degrees, min_quality=PmOptions::default().min_quality, boundary_weight=PmOptions::default().boundary_weight, corners=None, uv_weight=PmOptions::default().uv_weight))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn simplify<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    faces: Option<i64>,
    ratio: Option<f64>,
    error: Option<f64>,
    prune: Option<f64>,
    max_angle: f64,
    min_quality: f64,
    boundary_weight: f64,
    corners: Option<&Bound<'py, PyAny>>,
    uv_weight: f64,
) -> PyResult<Bound<'py, PyTuple>> {
    let faces = faces.map(|n| arrays::count("faces", n)).transpose()?;
    let goal = SimplifyGoal::one_of(faces, ratio, error, prune).map_err(input_error)?;
    let mesh = mesh_with_corners(v, f, corners)?;
    let options = PmOptions {
        max_normal_angle_degrees: max_angle,
        min_quality,
        boundary_weight,
        uv_weight,
        ..PmOptions::default()
    };
    let (result, _pruned) = py
        .detach(|| simplify_to_goal(&mesh, &goal, &options, &NoProgress))
        .map_err(input_error)?;
    if let Some(shortfall) = result.shortfall() {
        crate::warn(py, &shortfall)?;
    }
    let (v2, f2) = mesh_pair(py, &result.mesh);
    let map = index_array(py, &result.source_rows);
    let mut items = vec![v2.into_any(), f2.into_any(), map.into_any()];
    if corners.is_some() {
        items.push(corners_dict(py, &result.mesh)?.into_any());
    }
    PyTuple::new(py, items)
}

/// Subdivides a coarse mesh, as ``meshpyr subdivide`` (same options, same bits): ``scheme``
/// "mcm" (cascadic implicit mean-curvature motion, Diewald, Morigi and Rumpf) or "loop";
/// ``refine`` "quad" (1-to-4 splits, 4× faces per level) or "bisect" (2× per level);
/// ``solver`` "auto" (exact up to 250 000 output vertices, cascadic CG above), "exact",
/// "cg" or "jacobi"; ``width`` the filter-width constant c (σ = c · mean edge length;
/// larger values smooth and shrink more); ``local_width`` lets the width follow the local edge
/// length; ``finest_steps`` and ``beta`` set the cascadic schedule.
///
/// Returns ``(V2, F2)``: the input's vertices first (same order; repaired copies follow), the
/// new vertices after.
#[pyfunction]
#[pyo3(signature = (v, f, /, *, levels=SubdivSettings::default().levels as i64, scheme=SubdivSettings::default().scheme.name(), refine=SubdivSettings::default().refinement.name(), solver=SubdivSettings::default().solver.name(), width=SubdivSettings::default().width, local_width=SubdivSettings::default().local_width, finest_steps=SubdivSettings::default().finest_steps as i64, beta=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn subdivide<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    levels: i64,
    scheme: &str,
    refine: &str,
    solver: &str,
    width: f64,
    local_width: bool,
    finest_steps: i64,
    beta: Option<f64>,
) -> PyResult<MeshPair<'py>> {
    let settings = SubdivSettings {
        levels: arrays::count("levels", levels)?,
        scheme: Scheme::parse(scheme).map_err(input_error)?,
        refinement: Refinement::parse(refine).map_err(input_error)?,
        solver: SolverChoice::parse(solver).map_err(input_error)?,
        width,
        local_width,
        finest_steps: arrays::count("finest_steps", finest_steps)?,
        beta,
    };
    let mesh = arrays::mesh(v, f)?;
    let result = py.detach(|| {
        let built = Mesh::from_polygons(&mesh).map_err(|e| e.to_string())?;
        let options = settings.options(built.mesh.n_vertices());
        subdiv::subdivide(&built.mesh, &options, &NoProgress).map_err(|e| e.to_string())
    });
    let result = result.map_err(value_error)?;
    Ok((
        positions_array(py, &result.positions),
        triangles_array(py, &result.triangles),
    ))
}

/// Error of a processed mesh ``(V, F)`` against a reference ``(Vref, Fref)``, as ``meshpyr
/// compare --json``: a dict with e_v (area-weighted RMS distance from the result's vertices
/// to the reference surface), e_n (area-weighted RMS of the normal difference), hausdorff
/// (symmetric, sampled at vertices, edge midpoints and centroids) and its two one-sided
/// parts, the same divided by the reference's bounding-box diagonal (``*_rel``), e_v_over_l
/// (E_v in units of the reference's mean edge length), bbox_diagonal and mean_edge_length.
/// Distances below rounding noise of the diagonal read 0, as the CLI prints them.
///
/// With ``per_vertex=True`` the dict also holds ``distance``, a float64 array with the exact
/// distance from each row of V to the reference surface (model units, NaN for a non-finite
/// row), and ``per_vertex_distance``, its percentiles p50, p90, p99 and max, as ``meshpyr
/// compare --per-vertex`` writes and prints them.
///
/// Raises ValueError when the reference has no triangle with positive area.
#[pyfunction]
#[pyo3(signature = (v, f, v_ref, f_ref, /, *, per_vertex = false))]
pub(crate) fn compare<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    v_ref: &Bound<'py, PyAny>,
    f_ref: &Bound<'py, PyAny>,
    per_vertex: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let result = arrays::mesh(v, f)?;
    let reference = arrays::mesh(v_ref, f_ref)?;
    let measured = py.detach(|| {
        let result_mesh = Mesh::from_polygons(&result).map_err(|e| e.to_string())?;
        let reference = Mesh::from_polygons(&reference).map_err(|e| e.to_string())?;
        let comparison = meshpyr::metrics::compare(&result_mesh.mesh, &reference.mesh)
            .map_err(|e| e.to_string())?
            .without_rounding_noise();
        let field = if per_vertex {
            let surface = Reference::from_mesh(&reference.mesh).map_err(|e| e.to_string())?;
            Some(vertex_distances(&result.positions, &surface))
        } else {
            None
        };
        Ok::<_, String>((comparison, field))
    });
    let (comparison, field) = measured.map_err(value_error)?;
    let dict = to_dict(py, &comparison)?;
    if let Some(field) = field {
        if let Some(percentiles) = FieldPercentiles::of(&field) {
            dict.set_item("per_vertex_distance", to_dict(py, &percentiles)?)?;
        }
        dict.set_item("distance", PyArray1::from_vec(py, field))?;
    }
    Ok(dict)
}
