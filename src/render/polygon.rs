//! Pictures of [`PolygonMesh`]es as files hold them: polygons fanned into triangles, and the
//! colour values taken from a named per-vertex attribute.

use super::raster::{NO_IMAGE, PanelTexture};
use super::scene::{Panel, render_scene};
use super::texture::Textures;
use super::{Image, RenderOptions, Triangles};
use crate::mesh::PolygonMesh;
use crate::mesh::corners::MATERIAL_ATTRIBUTE;

/// Why a picture cannot be drawn.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RenderError {
    /// `color_by` names no per-vertex attribute of any of the meshes.
    #[error("no per-vertex attribute '{name}' in {meshes} (available: {available})")]
    UnknownAttribute {
        /// The attribute asked for.
        name: String,
        /// The meshes' labels (file names on the command line), comma-separated.
        meshes: String,
        /// The meshes' per-vertex attributes, comma-separated, or "none".
        available: String,
    },
    /// The colour range is empty, reversed or not finite.
    #[error("colour range {min}:{max} is not an interval (need finite MIN < MAX)")]
    BadRange {
        /// Lower end asked for.
        min: f64,
        /// Upper end asked for.
        max: f64,
    },
}

/// Draws `mesh` as one panel: [`render_meshes`] with no caption.
pub fn render_mesh(mesh: &PolygonMesh, options: &RenderOptions) -> Result<Image, RenderError> {
    render_meshes(&[("", mesh)], options)
}

/// Draws each `(label, mesh)` as a panel, left to right, with one camera for all (see
/// [`render_scene`](super::render_scene) for the layout). Polygons are fanned into triangles.
/// With `options.color_by`, that per-vertex attribute colours the surface over
/// `options.range` (default: its minimum and maximum over all meshes); meshes without it are
/// drawn in the plain surface colour (an input next to its coloured result), and it is an
/// error when no mesh has it.
/// The same meshes and options always give the same pixels.
pub fn render_meshes(
    meshes: &[(&str, &PolygonMesh)],
    options: &RenderOptions,
) -> Result<Image, RenderError> {
    let untextured: Vec<(&str, &PolygonMesh, Option<&Textures>)> =
        meshes.iter().map(|&(label, m)| (label, m, None)).collect();
    render_textured_meshes(&untextured, options)
}

/// [`render_meshes`] with each mesh's texture: a face whose material has an image in its
/// [`Textures`] ([`Textures::load`]) and whose corners have texture coordinates shows the
/// image, shaded like the rest of the surface; other faces, and every face where
/// `options.color_by` colours the surface, keep the plain or value colour.
pub fn render_textured_meshes(
    meshes: &[(&str, &PolygonMesh, Option<&Textures>)],
    options: &RenderOptions,
) -> Result<Image, RenderError> {
    if let Some((min, max)) = options.range
        && !(min.is_finite() && max.is_finite() && min < max)
    {
        return Err(RenderError::BadRange { min, max });
    }
    let plain: Vec<(&str, &PolygonMesh)> = meshes.iter().map(|&(l, m, _)| (l, m)).collect();
    let triangles: Vec<Vec<[u32; 3]>> = plain.iter().map(|(_, m)| fan_triangles(m)).collect();
    let values = attribute_values(&plain, options.color_by.as_deref())?;
    let corners: Vec<Option<FanTexture>> = meshes
        .iter()
        .map(|&(_, m, t)| t.filter(|t| !t.is_empty()).and_then(|_| fan_texture(m)))
        .collect();
    let panels: Vec<Panel<'_>> = meshes
        .iter()
        .zip(&triangles)
        .zip(&values)
        .zip(&corners)
        .map(|((((label, m, textures), t), v), c)| Panel {
            mesh: Triangles {
                positions: &m.positions,
                triangles: t,
            },
            label,
            values: v.as_deref(),
            texture: textures
                .zip(c.as_ref())
                .map(|(textures, (materials, uvs))| PanelTexture {
                    textures,
                    materials,
                    uvs,
                }),
        })
        .collect();
    Ok(render_scene(&panels, options))
}

/// Each mesh's values of the per-vertex attribute `name` (all `None` without a name); an
/// error when `name` is given and no mesh has it.
fn attribute_values(
    meshes: &[(&str, &PolygonMesh)],
    name: Option<&str>,
) -> Result<Vec<Option<Vec<f64>>>, RenderError> {
    let values: Vec<Option<Vec<f64>>> = meshes
        .iter()
        .map(|(_, m)| {
            let data = &name.and_then(|n| m.vertex_attribute(n))?.data;
            Some((0..data.len()).map(|i| data.get_f64(i)).collect())
        })
        .collect();
    match name {
        Some(name) if values.iter().all(Option::is_none) => Err(unknown_attribute(meshes, name)),
        _ => Ok(values),
    }
}

/// The error for an attribute no mesh has, listing the ones they do have.
fn unknown_attribute(meshes: &[(&str, &PolygonMesh)], name: &str) -> RenderError {
    let mut available: Vec<&str> = Vec::new();
    for (_, m) in meshes {
        for a in &m.vertex_attributes {
            if !available.contains(&a.name.as_str()) {
                available.push(&a.name);
            }
        }
    }
    let labels: Vec<&str> = meshes
        .iter()
        .map(|(label, _)| if label.is_empty() { "the mesh" } else { *label })
        .collect();
    RenderError::UnknownAttribute {
        name: name.to_string(),
        meshes: labels.join(", "),
        available: if available.is_empty() {
            "none".to_string()
        } else {
            available.join(", ")
        },
    }
}

/// Per fan triangle its material, and per triangle corner its texture coordinates.
type FanTexture = (Vec<u32>, Vec<[f32; 2]>);

/// Per fan triangle (as [`fan_triangles`] orders them) its material ([`NO_IMAGE`] when the
/// face has none or a corner lacks texture coordinates) and its corners' texture coordinates;
/// `None` when the mesh has no texture coordinates or no materials.
fn fan_texture(mesh: &PolygonMesh) -> Option<FanTexture> {
    let uv = mesh.corner_texcoords()?;
    let material = mesh.face_attribute(MATERIAL_ATTRIBUTE)?;
    let mut materials = Vec::with_capacity(mesh.n_triangles());
    let mut uvs = Vec::with_capacity(3 * mesh.n_triangles());
    for f in 0..mesh.n_faces() {
        let (s, e) = (
            mesh.face_starts[f] as usize,
            mesh.face_starts[f + 1] as usize,
        );
        let m = material.data.get_f64(f);
        for k in s + 1..e.saturating_sub(1) {
            let corners = [s, k, k + 1].map(&uv);
            let whole = m >= 0.0 && corners.iter().all(Option::is_some);
            materials.push(if whole { m as u32 } else { NO_IMAGE });
            uvs.extend(corners.map(|c| c.unwrap_or([0.0; 2])));
        }
    }
    Some((materials, uvs))
}

/// Each polygon as a fan of triangles around its first corner.
fn fan_triangles(mesh: &PolygonMesh) -> Vec<[u32; 3]> {
    let mut out = Vec::with_capacity(mesh.n_triangles());
    for face in mesh.faces() {
        for k in 1..face.len().saturating_sub(1) {
            out.push([face[0], face[k], face[k + 1]]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Attribute, AttributeData};
    use glam::DVec3;

    /// A unit square as one quad, with a per-vertex `height` equal to y.
    fn square() -> PolygonMesh {
        let mut m = PolygonMesh::new();
        m.positions = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        m.push_face(&[0, 1, 2, 3]);
        m.vertex_attributes.push(Attribute {
            name: "height".into(),
            data: AttributeData::F64(vec![0.0, 0.0, 1.0, 1.0]),
        });
        m
    }

    fn small() -> RenderOptions {
        RenderOptions {
            width: 40,
            height: 40,
            ..RenderOptions::default()
        }
    }

    #[test]
    fn polygons_are_fanned_into_triangles() {
        assert_eq!(fan_triangles(&square()), vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn unknown_attribute_names_the_mesh_and_lists_the_available_ones() {
        let options = RenderOptions {
            color_by: Some("distance".into()),
            ..small()
        };
        let err = render_meshes(&[("sq.ply", &square())], &options).unwrap_err();
        assert_eq!(
            err.to_string(),
            "no per-vertex attribute 'distance' in sq.ply (available: height)"
        );
    }

    #[test]
    fn empty_or_reversed_ranges_are_refused() {
        for (min, max) in [(1.0, 1.0), (2.0, 1.0), (0.0, f64::INFINITY)] {
            let options = RenderOptions {
                color_by: Some("height".into()),
                range: Some((min, max)),
                ..small()
            };
            let err = render_mesh(&square(), &options).unwrap_err();
            assert!(matches!(err, RenderError::BadRange { .. }), "{err}");
        }
    }

    #[test]
    fn values_run_through_the_colour_map_from_bottom_to_top() {
        let options = RenderOptions {
            color_by: Some("height".into()),
            ambient: 1.0,
            ..small()
        };
        let image = render_mesh(&square(), &options).unwrap();
        // Fully ambient light: the pixels are the colour map itself, dark purple at the
        // bottom row of the square (height 0) and yellow at the top (height 1).
        let (bottom, top) = (image.pixel(20, 37).unwrap(), image.pixel(20, 2).unwrap());
        assert!(bottom[2] > bottom[1] && bottom[0] < 100, "{bottom:?}");
        assert!(top[0] > 200 && top[1] > 200 && top[2] < 100, "{top:?}");
        // The colour bar adds rows under the panel.
        assert!(image.height > 40);
    }

    #[test]
    fn wireframe_draws_the_edges_and_only_them() {
        let plain = render_mesh(&square(), &small()).unwrap();
        let wired = RenderOptions {
            wireframe: true,
            ..small()
        };
        let wired = render_mesh(&square(), &wired).unwrap();
        let differing: Vec<(usize, usize)> = (0..40)
            .flat_map(|y| (0..40).map(move |x| (x, y)))
            .filter(|&(x, y)| plain.pixel(x, y) != wired.pixel(x, y))
            .collect();
        // The border and the diagonal of the fan, a pixel or so wide each.
        assert!(
            (100..=400).contains(&differing.len()),
            "{}",
            differing.len()
        );
        assert!(
            differing.contains(&(19, 20)),
            "the diagonal passes the centre"
        );
        assert!(!differing.contains(&(10, 25)), "inside a triangle");
    }
}
