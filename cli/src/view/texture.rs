//! The texture of a textured scan for the page: its image files as the browser decodes them,
//! and the drawing layout of its texture coordinates.
//!
//! The page draws indexed vertices, one texture coordinate each, while a textured scan has one
//! per face corner with seams where they differ. So the layout splits every vertex by its
//! distinct coordinates, for drawing only: each drawn vertex names the input vertex whose
//! position (and shading normal) it takes, so edits, normals and exports stay on the real
//! vertices. Triangles are grouped by their material's image, one draw call each.
//!
//! Only a scan with texture coordinates and a material image has any of this; an untextured
//! scan costs nothing. Images are read once when the editor opens, like the mesh.

use meshpyr::mesh::PolygonMesh;
use meshpyr::mesh::corners::MATERIAL_ATTRIBUTE;
use std::collections::HashMap;

/// Largest image file served: larger ones are left out (the page draws their faces plain).
const MAX_IMAGE_BYTES: u64 = 256 << 20;

/// The group of triangles drawn without an image.
const NO_IMAGE: u32 = u32::MAX;

/// One image file of a scan's materials.
pub(crate) struct ViewImage {
    /// The name its material gives (relative to the scan's folder).
    pub name: String,
    /// `image/png` or `image/jpeg`.
    pub media_type: &'static str,
    /// The file's bytes.
    pub bytes: Vec<u8>,
}

/// A textured scan's images and, per material, which image it shows.
pub(crate) struct ViewTexture {
    pub images: Vec<ViewImage>,
    /// Per material, its name and the index of its image in `images`.
    pub materials: Vec<(String, Option<usize>)>,
}

impl ViewTexture {
    /// The texture of `mesh`: `None` unless it has texture coordinates, a material per face
    /// and at least one image file that is there and is a PNG or JPEG.
    pub fn of(mesh: &PolygonMesh) -> Option<ViewTexture> {
        mesh.corner_texcoords().map(|_| ())?;
        mesh.face_attribute(MATERIAL_ATTRIBUTE)?;
        let folder = mesh.materials.folder.as_deref()?;
        let mut images: Vec<ViewImage> = Vec::new();
        let mut materials = Vec::new();
        for m in &mesh.materials.list {
            let image = m.texture.as_ref().and_then(|name| {
                if let Some(i) = images.iter().position(|x| &x.name == name) {
                    return Some(i);
                }
                let bytes = read_capped(&folder.join(name))?;
                let media_type = media_type(&bytes)?;
                images.push(ViewImage {
                    name: name.clone(),
                    media_type,
                    bytes,
                });
                Some(images.len() - 1)
            });
            materials.push((m.name.clone(), image));
        }
        (!images.is_empty()).then_some(ViewTexture { images, materials })
    }

    /// What `/api/info` says of it.
    pub fn info(&self) -> serde_json::Value {
        let materials: Vec<_> = self
            .materials
            .iter()
            .map(|(name, image)| serde_json::json!({"name": name, "image": image}))
            .collect();
        let images: Vec<&str> = self.images.iter().map(|i| i.name.as_str()).collect();
        serde_json::json!({"images": images, "materials": materials})
    }

    /// `/api/texcoords`: the drawing layout of `mesh`'s texture coordinates (see the module
    /// docs), little-endian: u32 counts of drawn vertices, triangles and groups; per drawn
    /// vertex its input vertex (u32); per drawn vertex `u`, `v` (f32); the triangles over
    /// drawn vertices (u32 triples), grouped; per group its image (u32, `0xFFFFFFFF` for
    /// none), first triangle and triangle count (u32).
    pub fn layout(&self, mesh: &PolygonMesh) -> Vec<u8> {
        let layout = split_layout(mesh, |f| self.face_image(mesh, f));
        let mut out = Vec::new();
        let n = layout.vertex_of.len();
        for x in [n, layout.triangles.len(), layout.groups.len()] {
            out.extend_from_slice(&(x as u32).to_le_bytes());
        }
        for &v in &layout.vertex_of {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for x in layout.uvs.iter().flatten() {
            out.extend_from_slice(&x.to_le_bytes());
        }
        for i in layout.triangles.iter().flatten() {
            out.extend_from_slice(&i.to_le_bytes());
        }
        for i in layout.groups.iter().flatten() {
            out.extend_from_slice(&i.to_le_bytes());
        }
        out
    }

    /// The image face `f` shows, or [`NO_IMAGE`].
    fn face_image(&self, mesh: &PolygonMesh, f: usize) -> u32 {
        let Some(m) = mesh.face_attribute(MATERIAL_ATTRIBUTE) else {
            return NO_IMAGE;
        };
        let m = m.data.get_f64(f);
        let image = (m >= 0.0)
            .then(|| self.materials.get(m as usize))
            .flatten()
            .and_then(|(_, image)| *image);
        image.map_or(NO_IMAGE, |i| i as u32)
    }
}

/// The layout of [`ViewTexture::layout`] before encoding.
pub(crate) struct SplitLayout {
    pub vertex_of: Vec<u32>,
    pub uvs: Vec<[f32; 2]>,
    pub triangles: Vec<[u32; 3]>,
    /// `[image, first triangle, count]`, by image (none last).
    pub groups: Vec<[u32; 3]>,
}

/// Splits `mesh`'s vertices by their corners' texture coordinates (compared by their bits)
/// and fans its polygons into triangles over the split vertices, grouped by `image_of` each
/// face (stable within a group). A corner without coordinates draws at `(0, 0)`, its face
/// without an image.
pub(crate) fn split_layout(mesh: &PolygonMesh, image_of: impl Fn(usize) -> u32) -> SplitLayout {
    let texcoord = mesh.corner_texcoords();
    let mut index: HashMap<(u32, [u32; 2]), u32> = HashMap::new();
    let (mut vertex_of, mut uvs) = (Vec::new(), Vec::new());
    let mut by_image: Vec<(u32, [u32; 3])> = Vec::with_capacity(mesh.n_triangles());
    for f in 0..mesh.n_faces() {
        let (s, e) = (
            mesh.face_starts[f] as usize,
            mesh.face_starts[f + 1] as usize,
        );
        let corners: Vec<Option<[f32; 2]>> = (s..e)
            .map(|c| texcoord.as_ref().and_then(|t| t(c)))
            .collect();
        let image = if corners.iter().all(Option::is_some) {
            image_of(f)
        } else {
            NO_IMAGE
        };
        let drawn: Vec<u32> = (s..e)
            .zip(&corners)
            .map(|(c, uv)| {
                let uv = uv.unwrap_or([0.0; 2]);
                let v = mesh.face_indices[c];
                *index.entry((v, uv.map(f32::to_bits))).or_insert_with(|| {
                    vertex_of.push(v);
                    uvs.push(uv);
                    vertex_of.len() as u32 - 1
                })
            })
            .collect();
        for k in 1..drawn.len().saturating_sub(1) {
            by_image.push((image, [drawn[0], drawn[k], drawn[k + 1]]));
        }
    }
    by_image.sort_by_key(|&(image, _)| image);
    let mut groups: Vec<[u32; 3]> = Vec::new();
    for (t, &(image, _)) in by_image.iter().enumerate() {
        match groups.last_mut() {
            Some(g) if g[0] == image => g[2] += 1,
            _ => groups.push([image, t as u32, 1]),
        }
    }
    SplitLayout {
        vertex_of,
        uvs,
        triangles: by_image.into_iter().map(|(_, t)| t).collect(),
        groups,
    }
}

/// The file's bytes, unless it is missing, unreadable or over [`MAX_IMAGE_BYTES`].
fn read_capped(path: &std::path::Path) -> Option<Vec<u8>> {
    let size = std::fs::metadata(path).ok()?.len();
    (size <= MAX_IMAGE_BYTES).then(|| std::fs::read(path).ok())?
}

/// The media type of an image file the browser decodes, by its first bytes.
fn media_type(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("image/png")
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some("image/jpeg")
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshpyr::mesh::CornerAttribute;
    use meshpyr::mesh::corners::TEXCOORD;

    /// Two triangles sharing an edge whose ends have different coordinates on each side.
    fn seamed() -> PolygonMesh {
        let p = vec![
            glam::DVec3::ZERO,
            glam::DVec3::X,
            glam::DVec3::Y,
            glam::DVec3::ONE,
        ];
        let mut m = PolygonMesh::from_triangles(p, &[[0, 1, 2], [2, 1, 3]]);
        let rows = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.5], [0.5, 0.0]];
        // Vertex 1 is at (1, 0) on both sides; vertex 2 at (0, 1), then (0.5, 0.5).
        let indices = vec![0, 1, 2, 3, 1, 4];
        m.corner_attributes.push(CornerAttribute::from_rows(
            TEXCOORD,
            ["u", "v"],
            &rows,
            indices,
        ));
        m
    }

    #[test]
    fn vertices_split_where_their_corners_differ_and_only_there() {
        let m = seamed();
        let layout = split_layout(&m, |f| f as u32);
        assert_eq!(layout.vertex_of, [0, 1, 2, 2, 3]);
        assert_eq!(layout.triangles, [[0, 1, 2], [3, 1, 4]]);
        assert_eq!(layout.uvs[3], [0.5, 0.5]);
        assert_eq!(layout.groups, [[0, 0, 1], [1, 1, 1]]);
    }

    #[test]
    fn triangles_group_by_image_with_the_imageless_last() {
        let m = seamed();
        let layout = split_layout(&m, |f| if f == 0 { NO_IMAGE } else { 0 });
        assert_eq!(layout.triangles, [[3, 1, 4], [0, 1, 2]]);
        assert_eq!(layout.groups, [[0, 0, 1], [NO_IMAGE, 1, 1]]);
        let mut bare = m.clone();
        bare.corner_attributes.clear();
        let layout = split_layout(&bare, |_| 0);
        assert_eq!(layout.vertex_of, [0, 1, 2, 3]);
        assert_eq!(layout.groups, [[NO_IMAGE, 0, 2]]);
    }
}
