//! `meshpyr.ProgressiveMesh`: the hierarchy of quadric-error collapses, cut at any level.

use crate::arrays::{index_array, positions_array, triangles_array};
use crate::errors::{input_error, value_error};
use crate::functions::mesh_with_corners;
use crate::pyramid::{level_in, mesh_tuple};
use meshpyr::mesh::SourceMap;
use meshpyr::pm::PmOptions;
use meshpyr::{NoProgress, PolygonMesh};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyRange, PyTuple};

/// A progressive mesh (Hoppe 1996): the vertices renumbered so that level ``n`` is the mesh on
/// the first ``n`` of them, from the base mesh (as far as legal quadric-error half-edge
/// collapses go) to the input. Collapses keep positions, so every level's vertices sit where
/// they were in the input.
///
/// ``ProgressiveMesh(V, F)`` builds it; ``levels`` is the range of valid ``n``;
/// ``mesh(n)`` gives level ``n`` as ``(V_n, F_n)``; ``vertex_map[i]`` is the index in V of
/// vertex ``i`` of every level.
///
/// ``corners=C`` (the dict of ``read(path, corners=True)``) makes the collapses keep the
/// texture seams and weigh the texture shift by ``uv_weight``, as ``meshpyr build`` does for
/// a textured file; ``mesh(n, corners=True)`` then gives ``(V_n, F_n, C_n)`` with the level's
/// corners dict.
#[pyclass(module = "meshpyr", frozen)]
pub(crate) struct ProgressiveMesh {
    pm: meshpyr::ProgressiveMesh,
    /// Input row of each PM vertex.
    rows: Vec<u32>,
    /// Built with corners: the input and the builder's map back to it, which the levels'
    /// corners come from (without, the levels have none and nothing is kept).
    textured: Option<(PolygonMesh, SourceMap)>,
}

#[pymethods]
impl ProgressiveMesh {
    #[new]
    #[pyo3(signature = (v, f, /, *, corners=None, uv_weight=PmOptions::default().uv_weight))]
    fn new(
        py: Python<'_>,
        v: &Bound<'_, PyAny>,
        f: &Bound<'_, PyAny>,
        corners: Option<&Bound<'_, PyAny>>,
        uv_weight: f64,
    ) -> PyResult<Self> {
        let input = mesh_with_corners(v, f, corners)?;
        let keep_input = corners.is_some();
        let options = PmOptions {
            uv_weight,
            ..PmOptions::default()
        };
        py.detach(|| {
            let (pm, source) =
                meshpyr::ProgressiveMesh::from_polygons(&input, &options, &NoProgress)
                    .map_err(input_error)?;
            // PM vertex -> mesh slot -> input row (copies made by the builder's repairs map to
            // the vertex they copy).
            let rows = pm
                .pm_to_mesh()
                .iter()
                .map(|&slot| source.vertex_source[slot as usize])
                .collect();
            let textured = keep_input.then_some((input, source));
            Ok(ProgressiveMesh { pm, rows, textured })
        })
    }

    /// The valid levels, ``range(base, finest + 1)``, as vertex counts.
    #[getter]
    fn levels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyRange>> {
        let (base, finest) = (self.pm.n_base_vertices(), self.pm.n_vertices());
        PyRange::new(py, base as isize, finest as isize + 1)
    }

    /// Index in V of each vertex of the hierarchy, int64: vertex ``i`` of ``mesh(n)`` is
    /// ``V[vertex_map[i]]``.
    #[getter]
    fn vertex_map<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        index_array(py, &self.rows[..self.pm.n_vertices()])
    }

    /// Level ``n`` (a vertex count in ``levels``) as ``(V_n, F_n)``: the first ``n`` vertices
    /// of the hierarchy at their input positions and the triangles among them, in the order
    /// of the input's triangles. With ``corners=True``, ``(V_n, F_n, C_n)``: C_n is the
    /// level's corners dict, each triangle keeping its material and the texture coordinates of
    /// its vertices on its own side of every seam (empty without the ``corners`` it was
    /// built with).
    #[pyo3(signature = (n, /, *, corners=false))]
    fn mesh<'py>(&self, py: Python<'py>, n: i64, corners: bool) -> PyResult<Bound<'py, PyTuple>> {
        let (base, finest) = (self.pm.n_base_vertices(), self.pm.n_vertices());
        let n = level_in(n, &(base..=finest))?;
        if let (true, Some((input, source))) = (corners, &self.textured) {
            let level = py
                .detach(|| meshpyr::pm::level_mesh(&self.pm, input, source, n))
                .map_err(|e| value_error(e.to_string()))?;
            return mesh_tuple(py, &level, true);
        }
        let tris = py.detach(|| self.pm.level_triangles(n));
        let mut items = vec![
            positions_array(py, &self.pm.original_positions()[..n]).into_any(),
            triangles_array(py, &tris).into_any(),
        ];
        if corners {
            items.push(PyDict::new(py).into_any());
        }
        PyTuple::new(py, items)
    }

    fn __repr__(&self) -> String {
        format!(
            "<meshpyr.ProgressiveMesh: levels {}..={}, {} to {} faces>",
            self.pm.n_base_vertices(),
            self.pm.n_vertices(),
            self.pm.n_base_faces(),
            self.pm.n_faces()
        )
    }
}
