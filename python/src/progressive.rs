//! `meshpyr.ProgressiveMesh`: the hierarchy of quadric-error collapses, cut at any level.

use crate::arrays::{self, index_array, positions_array, triangles_array};
use crate::errors::{input_error, value_error};
use crate::functions::MeshPair;
use meshpyr::NoProgress;
use meshpyr::pm::PmOptions;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyRange;

/// A progressive mesh (Hoppe 1996): the vertices renumbered so that level ``n`` is the mesh on
/// the first ``n`` of them, from the base mesh (as far as legal quadric-error half-edge
/// collapses go) to the input. Collapses keep positions, so every level's vertices sit where
/// they were in the input.
///
/// ``ProgressiveMesh(V, F)`` builds it; ``levels`` is the range of valid ``n``;
/// ``mesh(n)`` gives level ``n`` as ``(V_n, F_n)``; ``vertex_map[i]`` is the index in V of
/// vertex ``i`` of every level.
#[pyclass(module = "meshpyr", frozen)]
pub(crate) struct ProgressiveMesh {
    pm: meshpyr::ProgressiveMesh,
    /// Input row of each PM vertex.
    rows: Vec<u32>,
}

#[pymethods]
impl ProgressiveMesh {
    #[new]
    #[pyo3(signature = (v, f, /))]
    fn new(py: Python<'_>, v: &Bound<'_, PyAny>, f: &Bound<'_, PyAny>) -> PyResult<Self> {
        let mesh = arrays::mesh(v, f)?;
        py.detach(|| {
            let (pm, source) =
                meshpyr::ProgressiveMesh::from_polygons(&mesh, &PmOptions::default(), &NoProgress)
                    .map_err(input_error)?;
            // PM vertex -> mesh slot -> input row (copies made by the builder's repairs map to
            // the vertex they copy).
            let rows = pm
                .pm_to_mesh()
                .iter()
                .map(|&slot| source.vertex_source[slot as usize])
                .collect();
            Ok(ProgressiveMesh { pm, rows })
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
    /// of the input's triangles.
    fn mesh<'py>(&self, py: Python<'py>, n: i64) -> PyResult<MeshPair<'py>> {
        let (base, finest) = (self.pm.n_base_vertices(), self.pm.n_vertices());
        if !usize::try_from(n).is_ok_and(|n| (base..=finest).contains(&n)) {
            return Err(value_error(format!(
                "level {n} is outside this mesh's levels {base}..={finest}"
            )));
        }
        let n = n as usize;
        let tris = py.detach(|| self.pm.level_triangles(n));
        Ok((
            positions_array(py, &self.pm.original_positions()[..n]),
            triangles_array(py, &tris),
        ))
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
