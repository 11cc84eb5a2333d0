//! What a textured scan adds to its polygons: per-corner data (texture coordinates and normals
//! with their seams), a material per face and named face groups.
//!
//! The model, in [`PolygonMesh`]:
//! - [`CornerAttribute`]: a pool of values (columns such as `u`,`v` or `nx`,`ny`,`nz`) and one
//!   pool index per entry of `face_indices`. Corners on the two sides of a seam index different
//!   pool rows; corners that share a value may share a row, as OBJ's `vt`/`vn` indices do, so an
//!   OBJ file reads back to the same pools and indices it was written from. [`NO_VALUE`] marks a
//!   corner without one (OBJ allows faces with and without `vt` in one file).
//! - the material of a face is the face attribute [`MATERIAL_ATTRIBUTE`] (`texnumber`, as PLY
//!   files from MeshLab name it; `int`, −1 for none) indexing [`Materials::list`].
//! - OBJ groups and objects are the face attributes [`GROUP_ATTRIBUTE`] and
//!   [`OBJECT_ATTRIBUTE`] (`int`, −1 for none) indexing [`PolygonMesh::group_names`] and
//!   [`PolygonMesh::object_names`]; smoothing groups are [`SMOOTHING_ATTRIBUTE`] (`int`, 0 for
//!   off).
//! - other per-face lists of a PLY file are kept opaque in [`PolygonMesh::face_lists`].
//!
//! Being face attributes, materials and groups follow faces wherever faces are gathered, and a
//! PLY file stores them as ordinary face properties. An index outside its table (a sloppy
//! file's) is kept as it is; an OBJ writer names it `material7`, `group7`, ….

use std::path::PathBuf;

use super::polygon::{Attribute, AttributeData, PolygonMesh};

/// The pool index of a corner that has no value.
pub const NO_VALUE: u32 = u32::MAX;

/// The corner attribute of texture coordinates (columns `u`, `v`).
pub const TEXCOORD: &str = "texcoord";
/// The corner attribute of normals (columns `nx`, `ny`, `nz`).
pub const NORMAL: &str = "normal";
/// The face attribute holding each face's material index.
pub const MATERIAL_ATTRIBUTE: &str = "texnumber";
/// The face attribute holding each face's OBJ group (`g`) index.
pub const GROUP_ATTRIBUTE: &str = "obj_group";
/// The face attribute holding each face's OBJ object (`o`) index.
pub const OBJECT_ATTRIBUTE: &str = "obj_object";
/// The face attribute holding each face's OBJ smoothing group (`s`; 0 is off).
pub const SMOOTHING_ATTRIBUTE: &str = "obj_smoothing";

/// Values per face corner, stored as a pool and an index per corner (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CornerAttribute {
    /// [`TEXCOORD`], [`NORMAL`] or another name.
    pub name: String,
    /// The pool: columns of equal length (e.g. `u` and `v`).
    pub columns: Vec<Attribute>,
    /// One pool row per entry of [`PolygonMesh::face_indices`], or [`NO_VALUE`].
    pub indices: Vec<u32>,
}

impl CornerAttribute {
    /// The attribute `name` with `float` columns named `columns`, pool rows `rows` and one pool
    /// row (or [`NO_VALUE`]) per corner in `indices`: e.g.
    /// `CornerAttribute::from_rows(TEXCOORD, ["u", "v"], &[[0.0, 0.0], [1.0, 0.0]], indices)`.
    pub fn from_rows<const N: usize>(
        name: &str,
        columns: [&str; N],
        rows: &[[f32; N]],
        indices: Vec<u32>,
    ) -> CornerAttribute {
        let columns = columns
            .iter()
            .enumerate()
            .map(|(k, column)| Attribute {
                name: (*column).into(),
                data: AttributeData::F32(rows.iter().map(|r| r[k]).collect()),
            })
            .collect();
        CornerAttribute {
            name: name.into(),
            columns,
            indices,
        }
    }

    /// Number of pool rows.
    pub fn pool_len(&self) -> usize {
        self.columns.first().map_or(0, |c| c.data.len())
    }

    /// The pool row of corner `corner` (an index into `face_indices`), if it has a value.
    pub fn row(&self, corner: usize) -> Option<usize> {
        let r = self.indices[corner];
        (r != NO_VALUE).then_some(r as usize)
    }

    /// The value of corner `corner`, every column widened to f64.
    pub fn value(&self, corner: usize) -> Option<Vec<f64>> {
        let r = self.row(corner)?;
        Some(self.columns.iter().map(|c| c.data.get_f64(r)).collect())
    }

    /// Number of corners with a value.
    pub fn n_valued(&self) -> usize {
        self.indices.iter().filter(|&&i| i != NO_VALUE).count()
    }

    /// The invariants for a mesh of `corners` face corners.
    fn check(&self, corners: usize) -> Result<(), String> {
        let pool = self.pool_len();
        if self.columns.iter().any(|c| c.data.len() != pool) {
            return Err(format!(
                "corner attribute {} has columns of different lengths",
                self.name
            ));
        }
        if self.indices.len() != corners {
            return Err(format!(
                "corner attribute {} has {} indices for {corners} corners",
                self.name,
                self.indices.len()
            ));
        }
        if let Some(&i) = self
            .indices
            .iter()
            .find(|&&i| i != NO_VALUE && i as usize >= pool)
        {
            return Err(format!(
                "corner attribute {} has index {i} but {pool} values",
                self.name
            ));
        }
        Ok(())
    }
}

/// One material: the name a face's `usemtl` gives and the image its diffuse map names.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// OBJ `usemtl` name (one token).
    pub name: String,
    /// The diffuse image (OBJ `map_Kd`, PLY `TextureFile`) relative to the mesh file's folder
    /// (see [`Materials::folder`]), or absolute.
    pub texture: Option<String>,
}

/// The materials a mesh's faces index through [`MATERIAL_ATTRIBUTE`], and the files that
/// define them.
///
/// Paths are as the file wrote them, relative to [`Materials::folder`]. Writers to a path
/// in another folder rewrite relative paths so that they still reach the same files
/// (`crate::io` says how); the files themselves are referenced, never rewritten.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Materials {
    /// OBJ `mtllib` files.
    pub libraries: Vec<String>,
    /// Materials in the order faces index them.
    pub list: Vec<Material>,
    /// The folder relative paths start from (the read file's folder, absolute); `None` for a
    /// mesh not read from a file, whose paths are written as they are.
    pub folder: Option<PathBuf>,
}

impl Materials {
    /// True when there is neither a material nor a library.
    pub fn is_empty(&self) -> bool {
        self.libraries.is_empty() && self.list.is_empty()
    }
}

impl PolygonMesh {
    /// Looks up a corner attribute by name.
    pub fn corner_attribute(&self, name: &str) -> Option<&CornerAttribute> {
        self.corner_attributes.iter().find(|a| a.name == name)
    }

    /// The texture coordinates of a face corner (an index into `face_indices`): the corner
    /// attribute [`TEXCOORD`], or else the vertex's `u`, `v` columns (where an OBJ file's `vt`
    /// follow its `v` one to one, the reader keeps them per vertex). `None` when the mesh has
    /// neither; the function gives `None` for a corner without a value.
    pub fn corner_texcoords(&self) -> Option<impl Fn(usize) -> Option<[f32; 2]> + '_> {
        let corner = self
            .corner_attribute(TEXCOORD)
            .filter(|a| a.columns.len() >= 2);
        let vertex = self.vertex_attribute("u").zip(self.vertex_attribute("v"));
        if corner.is_none() && vertex.is_none() {
            return None;
        }
        Some(move |c: usize| match (corner, vertex) {
            (Some(a), _) => a
                .row(c)
                .map(|r| [0, 1].map(|k| a.columns[k].data.get_f64(r) as f32)),
            (None, Some((u, v))) => {
                let i = self.face_indices[c] as usize;
                Some([u.data.get_f64(i) as f32, v.data.get_f64(i) as f32])
            }
            (None, None) => None,
        })
    }

    /// Looks up a per-face attribute by name.
    pub fn face_attribute(&self, name: &str) -> Option<&Attribute> {
        self.face_attributes.iter().find(|a| a.name == name)
    }

    /// The invariants of the corner attributes and face lists.
    pub(super) fn check_corners(&self) -> Result<(), String> {
        for a in &self.corner_attributes {
            a.check(self.face_indices.len())?;
        }
        for l in &self.face_lists {
            if l.starts.len() != self.n_faces() + 1
                || l.starts.first() != Some(&0)
                || *l.starts.last().unwrap_or(&0) as usize != l.items.len()
                || l.starts.windows(2).any(|w| w[0] > w[1])
            {
                return Err(format!("face list {} has inconsistent offsets", l.name));
            }
        }
        Ok(())
    }

    /// The same mesh keeping the faces `kept` (in that order): polygons, face attributes,
    /// face lists and the corner attributes of their corners.
    pub(crate) fn with_faces(&self, kept: &[u32]) -> PolygonMesh {
        let mut out = PolygonMesh {
            face_starts: vec![0],
            face_indices: Vec::new(),
            face_attributes: Vec::new(),
            corner_attributes: Vec::new(),
            face_lists: Vec::new(),
            ..self.clone()
        };
        let mut corners = Vec::new();
        for &f in kept {
            let (s, e) = (
                self.face_starts[f as usize],
                self.face_starts[f as usize + 1],
            );
            out.push_face(self.face(f as usize));
            corners.extend(s..e);
        }
        out.face_attributes = self
            .face_attributes
            .iter()
            .map(|a| a.gathered(kept))
            .collect();
        out.corner_attributes = self
            .corner_attributes
            .iter()
            .map(|a| CornerAttribute {
                indices: corners.iter().map(|&c| a.indices[c as usize]).collect(),
                ..a.clone()
            })
            .collect();
        out.face_lists = self.face_lists.iter().map(|l| l.gathered(kept)).collect();
        out
    }
}
