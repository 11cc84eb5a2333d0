//! numpy arrays in and out: `V` float64 `(n, 3)`, `F` integer `(m, 3)`, checked before any
//! work (shape, dtype, NaN or Inf, indices out of range) so that bad input is a `ValueError`,
//! never a crash.

use crate::errors::value_error;
use glam::DVec3;
use meshpyr::PolygonMesh;
use numpy::ndarray::Array2;
use numpy::{
    PyArray1, PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

/// `np.asarray(obj)` as an untyped array (lists and other array-likes are accepted too); the
/// errors name it `name`, of shape `shape`.
pub(crate) fn as_array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    shape: &str,
) -> PyResult<Bound<'py, PyUntypedArray>> {
    let numpy = obj.py().import("numpy")?;
    let array = numpy
        .call_method1("asarray", (obj,))
        .map_err(|e| value_error(format!("{name} must be an array of shape {shape}: {e}")))?;
    array
        .cast_into::<PyUntypedArray>()
        .map_err(|_| value_error(format!("{name} must be a numpy array")))
}

/// Checks that `array` has shape `(n, 3)`; returns `n`.
fn rows_of_three(array: &Bound<'_, PyUntypedArray>, name: &str) -> PyResult<usize> {
    let shape = array.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(value_error(format!(
            "{name} must have shape (n, 3), got {}",
            shape_text(shape)
        )));
    }
    Ok(shape[0])
}

fn shape_text(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
    match parts.len() {
        1 => format!("({},)", parts[0]),
        _ => format!("({})", parts.join(", ")),
    }
}

/// `array.astype(dtype)` as a typed two-dimensional array.
fn converted<'py, T: numpy::Element>(
    array: &Bound<'py, PyUntypedArray>,
    dtype: &str,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let typed = array.call_method1("astype", (dtype,))?;
    Ok(typed.cast_into::<PyArray2<T>>()?)
}

/// The vertex positions `V`: float64 (float32 and float16 are widened exactly), shape `(n, 3)`,
/// every coordinate finite.
pub(crate) fn vertices(obj: &Bound<'_, PyAny>) -> PyResult<Vec<DVec3>> {
    let array = as_array(obj, "V", "(n, 3)")?;
    rows_of_three(&array, "V")?;
    let dtype = array.dtype();
    if dtype.kind() != b'f' {
        return Err(value_error(format!(
            "V must be a float array (float64; float32 is widened), got dtype {}",
            dtype
        )));
    }
    let typed = converted::<f64>(&array, "float64")?;
    let readonly = typed.try_readonly()?;
    let view = readonly.as_array();
    let mut positions = Vec::with_capacity(view.nrows());
    for (i, row) in view.rows().into_iter().enumerate() {
        let p = DVec3::new(row[0], row[1], row[2]);
        if !p.is_finite() {
            return Err(value_error(format!(
                "V[{i}] = [{}, {}, {}] is not finite (NaN or Inf)",
                p.x, p.y, p.z
            )));
        }
        positions.push(p);
    }
    Ok(positions)
}

/// The triangles `F`: any integer dtype, shape `(m, 3)`, every index in `0..n_vertices`.
pub(crate) fn triangles(obj: &Bound<'_, PyAny>, n_vertices: usize) -> PyResult<Vec<[u32; 3]>> {
    let array = as_array(obj, "F", "(n, 3)")?;
    rows_of_three(&array, "F")?;
    let dtype = array.dtype();
    let out_of_range = |i: usize, index: String| {
        value_error(format!(
            "F[{i}] holds index {index}, outside the {n_vertices} vertices of V (0..{n_vertices})"
        ))
    };
    let mut tris = Vec::new();
    match dtype.kind() {
        b'i' => {
            let typed = converted::<i64>(&array, "int64")?;
            let readonly = typed.try_readonly()?;
            for (i, row) in readonly.as_array().rows().into_iter().enumerate() {
                let mut t = [0u32; 3];
                for (k, &x) in row.iter().enumerate() {
                    if x < 0 || x as u64 >= n_vertices as u64 {
                        return Err(out_of_range(i, x.to_string()));
                    }
                    t[k] = x as u32;
                }
                tris.push(t);
            }
        }
        b'u' => {
            let typed = converted::<u64>(&array, "uint64")?;
            let readonly = typed.try_readonly()?;
            for (i, row) in readonly.as_array().rows().into_iter().enumerate() {
                let mut t = [0u32; 3];
                for (k, &x) in row.iter().enumerate() {
                    if x >= n_vertices as u64 {
                        return Err(out_of_range(i, x.to_string()));
                    }
                    t[k] = x as u32;
                }
                tris.push(t);
            }
        }
        _ => {
            return Err(value_error(format!(
                "F must be an integer array (vertex indices), got dtype {}",
                dtype
            )));
        }
    }
    Ok(tris)
}

/// `(V, F)` checked and turned into a triangle mesh.
pub(crate) fn mesh(v: &Bound<'_, PyAny>, f: &Bound<'_, PyAny>) -> PyResult<PolygonMesh> {
    let positions = vertices(v)?;
    if positions.len() >= u32::MAX as usize {
        return Err(value_error("V has more than 2^32 - 1 vertices"));
    }
    let tris = triangles(f, positions.len())?;
    Ok(PolygonMesh::from_triangles(positions, &tris))
}

/// Positions as a float64 `(n, 3)` array.
pub(crate) fn positions_array<'py>(py: Python<'py>, p: &[DVec3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.iter().flat_map(|x| x.to_array()).collect();
    let array = Array2::from_shape_vec((p.len(), 3), flat).expect("3 values per row");
    PyArray2::from_owned_array(py, array)
}

/// Triangles as an int64 `(m, 3)` array.
pub(crate) fn triangles_array<'py>(py: Python<'py>, t: &[[u32; 3]]) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = t.iter().flatten().map(|&i| i64::from(i)).collect();
    let array = Array2::from_shape_vec((t.len(), 3), flat).expect("3 values per row");
    PyArray2::from_owned_array(py, array)
}

/// Indices as an int64 array.
pub(crate) fn index_array<'py>(py: Python<'py>, rows: &[u32]) -> Bound<'py, PyArray1<i64>> {
    let v: Vec<i64> = rows.iter().map(|&i| i64::from(i)).collect();
    PyArray1::from_vec(py, v)
}

/// A file-level mesh as `(V, F)`: polygons fan-triangulated from their first corner, as the
/// library's mesh builder does, so `(V, F)` builds the same hierarchy as the file.
pub(crate) fn mesh_arrays(mesh: &PolygonMesh) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut tris = Vec::with_capacity(mesh.n_triangles());
    for face in mesh.faces() {
        for k in 1..face.len().saturating_sub(1) {
            tris.push([face[0], face[k], face[k + 1]]);
        }
    }
    (mesh.positions.clone(), tris)
}

/// A count or level given as a Python int: negative values are a `ValueError` (not the
/// `OverflowError` of a plain unsigned conversion).
pub(crate) fn count(name: &str, value: i64) -> PyResult<usize> {
    usize::try_from(value)
        .map_err(|_| value_error(format!("{name} must be a count >= 0, got {value}")))
}
