//! The mesh exactly as a file stores it: positions, polygons and attribute columns.
//!
//! [`PolygonMesh`] is the user's data. Readers fill it without changing anything (no welding, no
//! reordering, unreferenced vertices kept) and writers emit it unchanged, so a read → write trip
//! keeps vertex count, vertex order, face order and extra properties, and a textured scan's
//! per-corner data, materials and groups ([`crate::mesh::corners`]). Processing happens on the
//! half-edge [`crate::mesh::Mesh`] built from it; results are mapped back onto these vertices.

use glam::DVec3;

use super::corners::{CornerAttribute, Materials};

/// How a file stores a scalar: the PLY scalar types, which also cover OBJ/OFF/STL needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ScalarType {
    /// `char` / `int8`
    I8,
    /// `uchar` / `uint8`
    U8,
    /// `short` / `int16`
    I16,
    /// `ushort` / `uint16`
    U16,
    /// `int` / `int32`
    I32,
    /// `uint` / `uint32`
    U32,
    /// `float` / `float32`
    F32,
    /// `double` / `float64`
    F64,
}

impl ScalarType {
    /// Size of one value in bytes.
    pub fn size(self) -> usize {
        match self {
            ScalarType::I8 | ScalarType::U8 => 1,
            ScalarType::I16 | ScalarType::U16 => 2,
            ScalarType::I32 | ScalarType::U32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }
}

/// One column of values, one value per vertex (or per face), in its stored type so that
/// writing it back is bit-exact.
#[derive(Clone, Debug, PartialEq)]
pub enum AttributeData {
    /// `char` values
    I8(Vec<i8>),
    /// `uchar` values
    U8(Vec<u8>),
    /// `short` values
    I16(Vec<i16>),
    /// `ushort` values
    U16(Vec<u16>),
    /// `int` values
    I32(Vec<i32>),
    /// `uint` values
    U32(Vec<u32>),
    /// `float` values
    F32(Vec<f32>),
    /// `double` values
    F64(Vec<f64>),
}

impl AttributeData {
    /// Number of values in the column.
    pub fn len(&self) -> usize {
        match self {
            AttributeData::I8(v) => v.len(),
            AttributeData::U8(v) => v.len(),
            AttributeData::I16(v) => v.len(),
            AttributeData::U16(v) => v.len(),
            AttributeData::I32(v) => v.len(),
            AttributeData::U32(v) => v.len(),
            AttributeData::F32(v) => v.len(),
            AttributeData::F64(v) => v.len(),
        }
    }

    /// True when the column holds no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The stored scalar type.
    pub fn scalar_type(&self) -> ScalarType {
        match self {
            AttributeData::I8(_) => ScalarType::I8,
            AttributeData::U8(_) => ScalarType::U8,
            AttributeData::I16(_) => ScalarType::I16,
            AttributeData::U16(_) => ScalarType::U16,
            AttributeData::I32(_) => ScalarType::I32,
            AttributeData::U32(_) => ScalarType::U32,
            AttributeData::F32(_) => ScalarType::F32,
            AttributeData::F64(_) => ScalarType::F64,
        }
    }

    /// Value `i` widened to f64 (exact for every stored type).
    pub fn get_f64(&self, i: usize) -> f64 {
        match self {
            AttributeData::I8(v) => v[i] as f64,
            AttributeData::U8(v) => v[i] as f64,
            AttributeData::I16(v) => v[i] as f64,
            AttributeData::U16(v) => v[i] as f64,
            AttributeData::I32(v) => v[i] as f64,
            AttributeData::U32(v) => v[i] as f64,
            AttributeData::F32(v) => v[i] as f64,
            AttributeData::F64(v) => v[i],
        }
    }

    /// Appends `x` converted to the column's type (exact when `x` is a value of that type, as
    /// the PLY reader's widened list items are).
    pub(crate) fn push_f64(&mut self, x: f64) {
        match self {
            AttributeData::I8(v) => v.push(x as i8),
            AttributeData::U8(v) => v.push(x as u8),
            AttributeData::I16(v) => v.push(x as i16),
            AttributeData::U16(v) => v.push(x as u16),
            AttributeData::I32(v) => v.push(x as i32),
            AttributeData::U32(v) => v.push(x as u32),
            AttributeData::F32(v) => v.push(x as f32),
            AttributeData::F64(v) => v.push(x),
        }
    }

    /// A new column holding the values at `rows`, in that order (used to carry attributes
    /// through simplification and compaction).
    pub(crate) fn gather(&self, rows: &[u32]) -> AttributeData {
        fn g<T: Copy>(v: &[T], rows: &[u32]) -> Vec<T> {
            rows.iter().map(|&r| v[r as usize]).collect()
        }
        match self {
            AttributeData::I8(v) => AttributeData::I8(g(v, rows)),
            AttributeData::U8(v) => AttributeData::U8(g(v, rows)),
            AttributeData::I16(v) => AttributeData::I16(g(v, rows)),
            AttributeData::U16(v) => AttributeData::U16(g(v, rows)),
            AttributeData::I32(v) => AttributeData::I32(g(v, rows)),
            AttributeData::U32(v) => AttributeData::U32(g(v, rows)),
            AttributeData::F32(v) => AttributeData::F32(g(v, rows)),
            AttributeData::F64(v) => AttributeData::F64(g(v, rows)),
        }
    }
}

/// A named per-vertex or per-face column (`red`, `nx`, `quality`, `u`, …).
#[derive(Clone, Debug, PartialEq)]
pub struct Attribute {
    /// Property name as in the file (OBJ texture coordinates are `u`,`v`; normals `nx`,`ny`,`nz`).
    pub name: String,
    /// The values, one per row.
    pub data: AttributeData,
}

impl Attribute {
    /// The same column with `rows[i]`'s value in row `i` (rows dropped or reordered).
    pub(crate) fn gathered(&self, rows: &[u32]) -> Attribute {
        Attribute {
            name: self.name.clone(),
            data: self.data.gather(rows),
        }
    }
}

/// A list-valued property of an extra element or an extra list property (kept opaque).
#[derive(Clone, Debug, PartialEq)]
pub struct ListProperty {
    /// Property name.
    pub name: String,
    /// Type of the per-row length.
    pub count_type: ScalarType,
    /// Type of the items.
    pub item_type: ScalarType,
    /// `starts[i]..starts[i+1]` indexes `items` for row `i`; `starts.len() == rows + 1`.
    pub starts: Vec<u32>,
    /// All items, widened to f64 (exact for every PLY scalar type).
    pub items: Vec<f64>,
}

impl ListProperty {
    /// The same property with row `rows[i]` in row `i`.
    pub(crate) fn gathered(&self, rows: &[u32]) -> ListProperty {
        let mut starts = Vec::with_capacity(rows.len() + 1);
        starts.push(0);
        let mut items = Vec::new();
        for &r in rows {
            let (s, e) = (self.starts[r as usize], self.starts[r as usize + 1]);
            items.extend_from_slice(&self.items[s as usize..e as usize]);
            starts.push(items.len() as u32);
        }
        ListProperty {
            starts,
            items,
            ..self.clone()
        }
    }
}

/// A property of an element that is neither `vertex` nor `face`, kept so that it survives a
/// read → write trip.
#[derive(Clone, Debug, PartialEq)]
pub enum ElementProperty {
    /// One scalar per row.
    Scalar(Attribute),
    /// A list per row.
    List(ListProperty),
}

/// A PLY element other than `vertex` and `face` (e.g. `edge`, `material`), kept verbatim.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtraElement {
    /// Element name.
    pub name: String,
    /// Number of rows.
    pub rows: usize,
    /// Properties in file order.
    pub properties: Vec<ElementProperty>,
}

/// A polygon mesh exactly as read from a file.
///
/// Invariants (checked by [`PolygonMesh::check`]): every index is `< positions.len()`, every
/// position is finite, `face_starts` is non-decreasing, starts at 0 and ends at
/// `face_indices.len()`, every attribute column has one row per vertex (or face), every corner
/// attribute one index per corner into its pool, every face list one row per face, and the
/// material, group and object attributes index their tables (see [`crate::mesh::corners`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolygonMesh {
    /// Vertex positions, widened to f64 (exact for f32 input).
    pub positions: Vec<DVec3>,
    /// How the file stored positions; writers use it so f32 data round-trips bit for bit.
    pub position_type: Option<ScalarType>,
    /// CSR offsets: polygon `f` is `face_indices[face_starts[f]..face_starts[f+1]]`.
    /// Always `faces + 1` entries (a single `0` for a mesh without faces).
    pub face_starts: Vec<u32>,
    /// Concatenated polygon vertex indices.
    pub face_indices: Vec<u32>,
    /// Per-vertex columns in file order (colours, normals, texture coordinates, scalars).
    pub vertex_attributes: Vec<Attribute>,
    /// Per-face columns in file order (materials and groups among them, see
    /// [`crate::mesh::corners`]).
    pub face_attributes: Vec<Attribute>,
    /// Per-corner data with seams: texture coordinates, normals (see [`CornerAttribute`]).
    pub corner_attributes: Vec<CornerAttribute>,
    /// Per-face list properties other than the indices and `texcoord` (PLY only), kept opaque.
    pub face_lists: Vec<ListProperty>,
    /// The materials faces index, and the files that define them.
    pub materials: Materials,
    /// OBJ group (`g`) names, indexed by the face attribute `obj_group`.
    pub group_names: Vec<String>,
    /// OBJ object (`o`) names, indexed by the face attribute `obj_object`.
    pub object_names: Vec<String>,
    /// Other elements (PLY only), kept verbatim.
    pub extra_elements: Vec<ExtraElement>,
    /// Header comments (PLY `comment`, OFF/OBJ `#` lines before the data), kept for writing.
    pub comments: Vec<String>,
}

impl PolygonMesh {
    /// An empty mesh (no vertices, no faces).
    pub fn new() -> Self {
        PolygonMesh {
            face_starts: vec![0],
            ..Default::default()
        }
    }

    /// A mesh from positions and triangles (no attributes).
    pub fn from_triangles(positions: Vec<DVec3>, triangles: &[[u32; 3]]) -> Self {
        let mut m = PolygonMesh::new();
        m.positions = positions;
        // Sized up front: growing by doubling copies (and page-faults) the arrays again.
        m.face_indices.reserve_exact(3 * triangles.len());
        m.face_starts.reserve_exact(triangles.len());
        for t in triangles {
            m.push_face(t);
        }
        m
    }

    /// A mesh taking ownership of positions and triangles (no attributes): the triangle
    /// array becomes the index array without a copy, which matters for the million-face
    /// outputs of subdivision.
    pub fn from_triangle_vec(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Self {
        let face_starts = (0..=triangles.len()).map(|t| 3 * t as u32).collect();
        PolygonMesh {
            positions,
            face_starts,
            face_indices: triangles.into_flattened(),
            ..Default::default()
        }
    }

    /// Number of vertices (including unreferenced ones).
    pub fn n_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of polygons.
    pub fn n_faces(&self) -> usize {
        self.face_starts.len().saturating_sub(1)
    }

    /// Vertex indices of polygon `f`.
    pub fn face(&self, f: usize) -> &[u32] {
        &self.face_indices[self.face_starts[f] as usize..self.face_starts[f + 1] as usize]
    }

    /// Iterator over all polygons.
    pub fn faces(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        (0..self.n_faces()).map(move |f| self.face(f))
    }

    /// Appends a polygon.
    pub fn push_face(&mut self, indices: &[u32]) {
        if self.face_starts.is_empty() {
            self.face_starts.push(0);
        }
        self.face_indices.extend_from_slice(indices);
        self.face_starts.push(self.face_indices.len() as u32);
    }

    /// Number of triangles after fan triangulation (an n-gon gives n − 2).
    pub fn n_triangles(&self) -> usize {
        self.faces().map(|f| f.len().saturating_sub(2)).sum()
    }

    /// Looks up a per-vertex attribute by name.
    pub fn vertex_attribute(&self, name: &str) -> Option<&Attribute> {
        self.vertex_attributes.iter().find(|a| a.name == name)
    }

    /// Adds a per-vertex attribute, or replaces the one with the same name where it stands
    /// (so the file's property order is kept). Fails, changing nothing, unless it has one
    /// value per vertex.
    pub fn set_vertex_attribute(&mut self, attribute: Attribute) -> Result<(), String> {
        if attribute.data.len() != self.n_vertices() {
            return Err(format!(
                "vertex attribute {} has {} rows for {} vertices",
                attribute.name,
                attribute.data.len(),
                self.n_vertices()
            ));
        }
        match self
            .vertex_attributes
            .iter_mut()
            .find(|a| a.name == attribute.name)
        {
            Some(existing) => *existing = attribute,
            None => self.vertex_attributes.push(attribute),
        }
        Ok(())
    }

    /// Checks the invariants listed on the type; readers call it before returning.
    pub fn check(&self) -> Result<(), String> {
        let nv = self.positions.len();
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("vertex {i} has a non-finite coordinate"));
        }
        if self.face_starts.first() != Some(&0)
            || *self.face_starts.last().unwrap_or(&0) as usize != self.face_indices.len()
        {
            return Err("face offsets are inconsistent".into());
        }
        if self.face_starts.windows(2).any(|w| w[0] > w[1]) {
            return Err("face offsets are not monotone".into());
        }
        if let Some(k) = self.face_indices.iter().position(|&i| i as usize >= nv) {
            return Err(format!(
                "face index {} out of range ({} vertices)",
                self.face_indices[k], nv
            ));
        }
        for a in &self.vertex_attributes {
            if a.data.len() != nv {
                return Err(format!(
                    "vertex attribute {} has {} rows",
                    a.name,
                    a.data.len()
                ));
            }
        }
        for a in &self.face_attributes {
            if a.data.len() != self.n_faces() {
                return Err(format!(
                    "face attribute {} has {} rows",
                    a.name,
                    a.data.len()
                ));
            }
        }
        self.check_corners()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_vertex_attribute_replaces_in_place_or_appends_and_checks_rows() {
        let mut m =
            PolygonMesh::from_triangles(vec![DVec3::ZERO, DVec3::X, DVec3::Y], &[[0, 1, 2]]);
        let column = |name: &str, v: f64, n: usize| Attribute {
            name: name.into(),
            data: AttributeData::F64(vec![v; n]),
        };
        m.set_vertex_attribute(column("a", 1.0, 3)).unwrap();
        m.set_vertex_attribute(column("b", 2.0, 3)).unwrap();
        m.set_vertex_attribute(column("a", 3.0, 3)).unwrap();
        let names: Vec<&str> = m
            .vertex_attributes
            .iter()
            .map(|a| a.name.as_str())
            .collect();
        assert_eq!(names, ["a", "b"]);
        assert_eq!(m.vertex_attribute("a").unwrap().data.get_f64(2), 3.0);
        assert!(m.set_vertex_attribute(column("c", 0.0, 2)).is_err());
        assert_eq!(m.vertex_attributes.len(), 2);
    }

    #[test]
    fn owned_and_borrowed_triangle_constructors_agree() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let t = vec![[0, 1, 2], [0, 3, 1], [1, 3, 2]];
        let owned = PolygonMesh::from_triangle_vec(p.clone(), t.clone());
        assert_eq!(owned, PolygonMesh::from_triangles(p.clone(), &t));
        assert_eq!(owned.face(2), &[1, 3, 2]);
        let empty = PolygonMesh::from_triangle_vec(p.clone(), Vec::new());
        assert_eq!(empty, PolygonMesh::from_triangles(p, &[]));
        assert_eq!(empty.n_faces(), 0);
    }
}
