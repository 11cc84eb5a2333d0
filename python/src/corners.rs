//! What a textured mesh holds beyond `(V, F)`, as a dict of numpy arrays and lists: per-corner
//! texture coordinates and normals (with their seams), a material and a group per triangle, and
//! the material files. `read(path, corners=True)` gives it, `write`, `info` and `simplify` take
//! it (`corners=C`).
//!
//! Every array is per triangle of `F` (polygons fan-triangulated from their first corner, as `F`
//! is), so it stays valid wherever `F` does: filters and edits keep `F`, `simplify` returns the
//! dict of its output. Keys (all optional when written):
//! - `texcoord`: (m, 3, 2) float, NaN for a corner without texture coordinates;
//! - `normal`: (m, 3, 3) float, NaN for a corner without a normal;
//! - `material`: (m,) int, an index into `materials` or -1; `materials`: a list of dicts
//!   `{"name": str, "texture": str or None}`; `material_libraries`: the OBJ `mtllib` files;
//!   `folder`: where relative paths start (the read file's folder) or None;
//! - `group`: (m,) int, an index into `groups` or -1; `groups`: a list of names.
//!
//! Floats keep their stored type (float32 or float64), so a file read and written back holds
//! the same bits; corners that share a value share one stored value, as OBJ's `vt` do.

use crate::arrays::as_array;
use crate::errors::value_error;
use meshpyr::PolygonMesh;
use meshpyr::mesh::corners::{GROUP_ATTRIBUTE, MATERIAL_ATTRIBUTE, NORMAL, TEXCOORD};
use meshpyr::mesh::{Attribute, AttributeData, CornerAttribute, Material, NO_VALUE};
use numpy::ndarray::{Array1, Array3};
use numpy::{PyArray1, PyArray3, PyArrayDescrMethods, PyArrayMethods};
use numpy::{PyUntypedArrayMethods, ToPyArray};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::collections::HashMap;
use std::path::PathBuf;

/// The keys a corners dict may hold.
const KEYS: [&str; 8] = [
    "texcoord",
    "normal",
    "material",
    "materials",
    "material_libraries",
    "folder",
    "group",
    "groups",
];

/// The polygon corner (an index into `face_indices`) of each triangle corner of the fan
/// triangulation, and the polygon of each triangle.
fn fan_corners(mesh: &PolygonMesh) -> (Vec<[usize; 3]>, Vec<u32>) {
    let mut corners = Vec::with_capacity(mesh.n_triangles());
    let mut faces = Vec::with_capacity(mesh.n_triangles());
    for f in 0..mesh.n_faces() {
        let start = mesh.face_starts[f] as usize;
        for k in 1..mesh.face(f).len().saturating_sub(1) {
            corners.push([start, start + k, start + k + 1]);
            faces.push(f as u32);
        }
    }
    (corners, faces)
}

/// The corners dict of `mesh` (see the module docs); empty for a mesh without any of it.
pub(crate) fn corners_dict<'py>(
    py: Python<'py>,
    mesh: &PolygonMesh,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    let (corners, faces) = fan_corners(mesh);
    if let Some(columns) = texcoord_columns(mesh) {
        dict.set_item("texcoord", corner_array(py, &corners, &columns))?;
    }
    if let Some(a) = mesh
        .corner_attribute(NORMAL)
        .filter(|a| a.columns.len() == 3)
    {
        let columns = PerCorner::Pooled(a);
        dict.set_item("normal", corner_array(py, &corners, &columns))?;
    }
    if let Some(a) = mesh.face_attribute(MATERIAL_ATTRIBUTE) {
        dict.set_item("material", face_array(py, a, &faces))?;
    }
    let materials = &mesh.materials;
    if !materials.is_empty() {
        let list = PyList::empty(py);
        for m in &materials.list {
            let entry = PyDict::new(py);
            entry.set_item("name", &m.name)?;
            entry.set_item("texture", &m.texture)?;
            list.append(entry)?;
        }
        dict.set_item("materials", list)?;
        dict.set_item("material_libraries", &materials.libraries)?;
        dict.set_item("folder", &materials.folder)?;
    }
    if let Some(a) = mesh.face_attribute(GROUP_ATTRIBUTE) {
        dict.set_item("group", face_array(py, a, &faces))?;
        dict.set_item("groups", &mesh.group_names)?;
    }
    Ok(dict)
}

/// Where a corner's value comes from: a pooled corner attribute, or per-vertex columns (an
/// OBJ whose `vt` follow its `v` one to one keeps them per vertex).
enum PerCorner<'a> {
    Pooled(&'a CornerAttribute),
    Vertex(&'a PolygonMesh, [&'a Attribute; 2]),
}

impl PerCorner<'_> {
    fn width(&self) -> usize {
        match self {
            PerCorner::Pooled(a) => a.columns.len(),
            PerCorner::Vertex(..) => 2,
        }
    }

    fn all_f32(&self) -> bool {
        let f32 = |a: &Attribute| matches!(a.data, AttributeData::F32(_));
        match self {
            PerCorner::Pooled(a) => a.columns.iter().all(f32),
            PerCorner::Vertex(_, columns) => columns.iter().all(|a| f32(a)),
        }
    }

    /// Column `k` of polygon corner `c`, NaN without a value.
    fn get(&self, c: usize, k: usize) -> f64 {
        match self {
            PerCorner::Pooled(a) => a.row(c).map_or(f64::NAN, |r| a.columns[k].data.get_f64(r)),
            PerCorner::Vertex(mesh, columns) => {
                columns[k].data.get_f64(mesh.face_indices[c] as usize)
            }
        }
    }
}

fn texcoord_columns(mesh: &PolygonMesh) -> Option<PerCorner<'_>> {
    if let Some(a) = mesh
        .corner_attribute(TEXCOORD)
        .filter(|a| a.columns.len() == 2)
    {
        return Some(PerCorner::Pooled(a));
    }
    let u = mesh.vertex_attribute("u")?;
    let v = mesh.vertex_attribute("v")?;
    Some(PerCorner::Vertex(mesh, [u, v]))
}

/// An (m, 3, width) array of the corners' values, float32 when every column is.
fn corner_array<'py>(
    py: Python<'py>,
    corners: &[[usize; 3]],
    values: &PerCorner<'_>,
) -> Bound<'py, PyAny> {
    let width = values.width();
    let flat: Vec<f64> = corners
        .iter()
        .flatten()
        .flat_map(|&c| (0..width).map(move |k| values.get(c, k)))
        .collect();
    let array =
        Array3::from_shape_vec((corners.len(), 3, width), flat).expect("width values per corner");
    if values.all_f32() {
        // Widened from f32, so the narrowing is exact.
        PyArray3::from_owned_array(py, array.mapv(|x| x as f32)).into_any()
    } else {
        PyArray3::from_owned_array(py, array).into_any()
    }
}

/// An (m,) int64 array of a face attribute gathered per triangle.
fn face_array<'py>(py: Python<'py>, a: &Attribute, faces: &[u32]) -> Bound<'py, PyArray1<i64>> {
    let values: Vec<i64> = faces
        .iter()
        .map(|&f| a.data.get_f64(f as usize) as i64)
        .collect();
    Array1::from_vec(values).to_pyarray(py)
}

/// Adds the corners dict `dict` to `mesh`, a triangle mesh made from `F` (one face per
/// triangle), checking every key, shape and index first.
pub(crate) fn apply(mesh: &mut PolygonMesh, dict: &Bound<'_, PyAny>) -> PyResult<()> {
    let dict = dict
        .cast::<PyDict>()
        .map_err(|_| value_error("corners must be a dict (as read(path, corners=True) gives)"))?;
    for key in dict.keys() {
        let key: String = key.extract()?;
        if !KEYS.contains(&key.as_str()) {
            return Err(value_error(format!(
                "corners has an unknown key {key:?}; the keys are {}",
                KEYS.join(", ")
            )));
        }
    }
    let m = mesh.n_faces();
    if let Some(array) = dict.get_item("texcoord")? {
        let attribute = corner_attribute(&array, "texcoord", TEXCOORD, &["u", "v"], m)?;
        mesh.corner_attributes.push(attribute);
    }
    if let Some(array) = dict.get_item("normal")? {
        let attribute = corner_attribute(&array, "normal", NORMAL, &["nx", "ny", "nz"], m)?;
        mesh.corner_attributes.push(attribute);
    }
    if let Some(list) = dict.get_item("materials")? {
        mesh.materials.list = materials(&list)?;
    }
    if let Some(list) = dict.get_item("material_libraries")? {
        mesh.materials.libraries = list
            .extract()
            .map_err(|_| value_error("corners[\"material_libraries\"] must be a list of str"))?;
    }
    if let Some(folder) = dict.get_item("folder")? {
        mesh.materials.folder = folder
            .extract::<Option<PathBuf>>()
            .map_err(|_| value_error("corners[\"folder\"] must be a path or None"))?;
    }
    if let Some(array) = dict.get_item("material")? {
        let n = mesh.materials.list.len();
        let data = table_indices(&array, "material", "materials", n, m)?;
        mesh.face_attributes.push(Attribute {
            name: MATERIAL_ATTRIBUTE.into(),
            data,
        });
    }
    if let Some(list) = dict.get_item("groups")? {
        mesh.group_names = list
            .extract()
            .map_err(|_| value_error("corners[\"groups\"] must be a list of str"))?;
    }
    if let Some(array) = dict.get_item("group")? {
        let n = mesh.group_names.len();
        let data = table_indices(&array, "group", "groups", n, m)?;
        mesh.face_attributes.push(Attribute {
            name: GROUP_ATTRIBUTE.into(),
            data,
        });
    }
    mesh.check().map_err(value_error)
}

fn materials(list: &Bound<'_, PyAny>) -> PyResult<Vec<Material>> {
    let bad = || {
        value_error(
            "corners[\"materials\"] must be a list of dicts {\"name\": str, \"texture\": str or None}",
        )
    };
    let mut out = Vec::new();
    for item in list.try_iter().map_err(|_| bad())? {
        let item = item?;
        let entry = item.cast::<PyDict>().map_err(|_| bad())?;
        let name: String = match entry.get_item("name")? {
            Some(n) => n.extract().map_err(|_| bad())?,
            None => return Err(bad()),
        };
        if name.is_empty() || name.chars().any(char::is_whitespace) {
            return Err(value_error(format!(
                "corners[\"materials\"] holds the name {name:?}: a material name is one word"
            )));
        }
        let texture: Option<String> = match entry.get_item("texture")? {
            Some(t) => t.extract().map_err(|_| bad())?,
            None => None,
        };
        out.push(Material { name, texture });
    }
    Ok(out)
}

/// A pooled corner attribute from an (m, 3, width) float array: equal values (bit for bit)
/// share a pool row, NaN rows have none.
fn corner_attribute(
    obj: &Bound<'_, PyAny>,
    key: &str,
    name: &str,
    columns: &[&str],
    m: usize,
) -> PyResult<CornerAttribute> {
    let width = columns.len();
    let array = as_array(
        obj,
        &format!("corners[{key:?}]"),
        &format!("(m, 3, {width})"),
    )?;
    if array.shape() != [m, 3, width] {
        return Err(value_error(format!(
            "corners[{key:?}] must have shape ({m}, 3, {width}) (a value per corner of F), got {:?}",
            array.shape()
        )));
    }
    let kind = array.dtype().kind();
    if kind != b'f' {
        return Err(value_error(format!(
            "corners[{key:?}] must be a float array, got dtype {}",
            array.dtype()
        )));
    }
    let single = array.dtype().itemsize() <= 4;
    let typed = array
        .call_method1("astype", ("float64",))?
        .cast_into::<PyArray3<f64>>()?;
    let readonly = typed.try_readonly()?;
    let view = readonly.as_array();
    let mut rows: HashMap<Vec<u64>, u32> = HashMap::new();
    let mut pool: Vec<Vec<f64>> = vec![Vec::new(); width];
    let mut indices = Vec::with_capacity(3 * m);
    for (t, triangle) in view.outer_iter().enumerate() {
        for (k, corner) in triangle.outer_iter().enumerate() {
            let value: Vec<f64> = corner.iter().copied().collect();
            let missing = value.iter().filter(|x| x.is_nan()).count();
            if missing == width {
                indices.push(NO_VALUE);
                continue;
            }
            if missing > 0 || value.iter().any(|x| x.is_infinite()) {
                return Err(value_error(format!(
                    "corners[{key:?}][{t}, {k}] = {value:?}: a corner's value is all finite or all NaN"
                )));
            }
            let bits: Vec<u64> = value.iter().map(|x| x.to_bits()).collect();
            let next = rows.len() as u32;
            let row = *rows.entry(bits).or_insert_with(|| {
                for (column, x) in pool.iter_mut().zip(&value) {
                    column.push(*x);
                }
                next
            });
            indices.push(row);
        }
    }
    let columns = columns
        .iter()
        .zip(pool)
        .map(|(name, values)| Attribute {
            name: (*name).into(),
            data: if single {
                AttributeData::F32(values.iter().map(|&x| x as f32).collect())
            } else {
                AttributeData::F64(values)
            },
        })
        .collect();
    Ok(CornerAttribute {
        name: name.into(),
        columns,
        indices,
    })
}

/// An (m,) int array of indices into a table of `n` entries (or -1), as an `int` column.
fn table_indices(
    obj: &Bound<'_, PyAny>,
    key: &str,
    table: &str,
    n: usize,
    m: usize,
) -> PyResult<AttributeData> {
    let array = as_array(obj, &format!("corners[{key:?}]"), "(m,)")?;
    if array.shape() != [m] {
        return Err(value_error(format!(
            "corners[{key:?}] must have shape ({m},) (one per triangle of F), got {:?}",
            array.shape()
        )));
    }
    if !matches!(array.dtype().kind(), b'i' | b'u') {
        return Err(value_error(format!(
            "corners[{key:?}] must be an integer array, got dtype {}",
            array.dtype()
        )));
    }
    let typed = array
        .call_method1("astype", ("int64",))?
        .cast_into::<PyArray1<i64>>()?;
    let readonly = typed.try_readonly()?;
    let mut out = Vec::with_capacity(m);
    for (t, &i) in readonly.as_array().iter().enumerate() {
        if i < -1 || i >= n as i64 {
            return Err(value_error(format!(
                "corners[{key:?}][{t}] = {i} is outside corners[{table:?}] (-1 for none, else 0..{n})"
            )));
        }
        out.push(i as i32);
    }
    Ok(AttributeData::I32(out))
}
