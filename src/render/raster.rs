//! The orthographic camera and the z-buffer rasteriser: one panel at a time, in triangle
//! order, single-threaded, so the pixels depend on nothing but the input.

use super::colormap::colormap;
use super::texture::{Textures, sample};
use super::{Image, RenderOptions, Shading, Triangles};
use glam::{DMat3, DVec3};

/// Colour of wireframe edges.
const WIRE: [u8; 3] = [45, 45, 45];
/// Colour of surface points whose value is missing or not finite.
const NO_VALUE: [u8; 3] = [150, 150, 150];
/// Half-width in pixels of a wireframe line on each side of an edge: a little over half a
/// pixel, so edges on pixel boundaries still light the pixels next to them.
const WIRE_HALF_WIDTH: f64 = 0.6;

/// Orthographic view: a rotation plus a scale and offset that map the model into the panel.
#[derive(Clone, Copy, Debug)]
pub(super) struct Camera {
    rotation: DMat3,
    centre: DVec3,
    scale: f64,
}

impl Camera {
    /// The view that fits the union of the meshes' bounding boxes (after rotation) into one
    /// panel.
    pub(super) fn fit(meshes: &[Triangles<'_>], options: &RenderOptions) -> Camera {
        let rotation = DMat3::from_rotation_x(options.pitch_degrees.to_radians())
            * DMat3::from_rotation_y(options.yaw_degrees.to_radians());
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for m in meshes {
            for t in m.triangles {
                for &i in t {
                    if let Some(&p) = m.positions.get(i as usize)
                        && p.is_finite()
                    {
                        let q = rotation * p;
                        lo = lo.min(q);
                        hi = hi.max(q);
                    }
                }
            }
        }
        if lo.x.is_nan() || lo.x > hi.x {
            return Camera {
                rotation,
                centre: DVec3::ZERO,
                scale: 1.0,
            };
        }
        let extent = (hi - lo).max(DVec3::splat(1e-300));
        let usable = 1.0 - 2.0 * options.margin.clamp(0.0, 0.45);
        let sx = usable * options.width as f64 / extent.x;
        let sy = usable * options.height as f64 / extent.y;
        Camera {
            rotation,
            centre: 0.5 * (lo + hi),
            scale: sx.min(sy),
        }
    }

    /// Pixel coordinates (x right, y down) and depth (larger = nearer).
    #[inline]
    fn project(&self, p: DVec3, width: usize, height: usize) -> DVec3 {
        let q = self.rotation * p - self.centre;
        DVec3::new(
            0.5 * width as f64 + q.x * self.scale,
            0.5 * height as f64 - q.y * self.scale,
            q.z,
        )
    }
}

/// How the surface of one panel is coloured: the lighting and, optionally, a value per vertex
/// mapped through the colour map over `range`, or else the images of a textured mesh.
pub(super) struct Paint<'a> {
    pub(super) values: Option<&'a [f64]>,
    pub(super) range: (f64, f64),
    pub(super) texture: Option<PanelTexture<'a>>,
}

/// The texture of one panel's triangles: per triangle its material's image and its corners'
/// texture coordinates.
#[derive(Clone, Copy, Debug)]
pub struct PanelTexture<'a> {
    /// The images, one per material.
    pub textures: &'a Textures,
    /// Per triangle, the material whose image it shows ([`NO_IMAGE`]: the plain colour).
    pub materials: &'a [u32],
    /// Per triangle corner (three per triangle), its texture coordinates `(u, v)`.
    pub uvs: &'a [[f32; 2]],
}

/// The material index of a triangle drawn without an image.
pub const NO_IMAGE: u32 = u32::MAX;

impl<'a> PanelTexture<'a> {
    /// The image and corner coordinates of triangle `t`, when it shows one.
    fn of(self, t: usize) -> Option<(&'a Image, [[f64; 2]; 3])> {
        let material = *self.materials.get(t)?;
        let image = self.textures.image(material as usize)?;
        let uv = self.uvs.get(3 * t..3 * t + 3)?;
        Some((image, [0, 1, 2].map(|k| uv[k].map(f64::from))))
    }
}

/// Draws one mesh into a panel of `options.width × options.height` seen by `camera`.
pub(super) fn draw_panel(
    mesh: Triangles<'_>,
    paint: &Paint<'_>,
    camera: &Camera,
    options: &RenderOptions,
) -> Image {
    let (w, h) = (options.width.max(1), options.height.max(1));
    let mut image = Image::new(w, h, options.background);
    let mut depth = vec![f64::NEG_INFINITY; w * h];
    let light = options.light.normalize_or_zero();
    let ambient = options.ambient.clamp(0.0, 1.0);
    let vertex_normals =
        (options.shading == Shading::Smooth).then(|| view_vertex_normals(mesh, camera));
    let n = mesh.positions.len();
    for (k, t) in mesh.triangles.iter().enumerate() {
        if t.iter().any(|&i| i as usize >= n) {
            continue;
        }
        let world = t.map(|i| mesh.positions[i as usize]);
        if world.iter().any(|p| !p.is_finite()) {
            continue;
        }
        let face_normal = (camera.rotation * (world[1] - world[0]).cross(world[2] - world[0]))
            .normalize_or_zero();
        let normals = vertex_normals
            .as_ref()
            .map_or([face_normal; 3], |vn| t.map(|i| vn[i as usize]));
        let values = paint
            .values
            .map(|v| t.map(|i| v.get(i as usize).copied().unwrap_or(f64::NAN)));
        // A value to colour by wins over the texture: the user asked for it.
        let texture = paint
            .texture
            .filter(|_| values.is_none())
            .and_then(|x| x.of(k));
        let shade_at = |b: [f64; 3]| {
            let normal = if vertex_normals.is_some() {
                (b[0] * normals[0] + b[1] * normals[1] + b[2] * normals[2]).normalize_or_zero()
            } else {
                face_normal
            };
            // Two-sided lighting: scans have holes, and back faces should not turn black.
            let shade = ambient + (1.0 - ambient) * normal.dot(light).abs();
            let base = match (values, texture) {
                (Some(v), _) => {
                    value_color(b[0] * v[0] + b[1] * v[1] + b[2] * v[2], paint.range).map(f64::from)
                }
                (None, Some((image, uv))) => {
                    let at = |c: usize| b[0] * uv[0][c] + b[1] * uv[1][c] + b[2] * uv[2][c];
                    sample(image, at(0), at(1))
                }
                (None, None) => options.color.map(f64::from),
            };
            base.map(|c| (c * shade).round().clamp(0.0, 255.0) as u8)
        };
        let s = world.map(|p| camera.project(p, w, h));
        rasterise(&mut image, &mut depth, s, options.wireframe, shade_at);
    }
    image
}

/// The colour of `value` on the colour map over `range` (clamped at its ends).
fn value_color(value: f64, (lo, hi): (f64, f64)) -> [u8; 3] {
    if !value.is_finite() {
        return NO_VALUE;
    }
    let t = if hi > lo {
        (value - lo) / (hi - lo)
    } else {
        0.5
    };
    colormap(t)
}

/// Unit vertex normals in view space: the sums of the incident faces' area-weighted normals.
fn view_vertex_normals(mesh: Triangles<'_>, camera: &Camera) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; mesh.positions.len()];
    for t in mesh.triangles {
        let Some(p) = corners(mesh, t) else { continue };
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    normals
        .into_iter()
        .map(|n| (camera.rotation * n).normalize_or_zero())
        .collect()
}

/// The triangle's corner positions, or `None` when an index is out of range or a corner is
/// not finite.
fn corners(mesh: Triangles<'_>, t: &[u32; 3]) -> Option<[DVec3; 3]> {
    let p = [
        *mesh.positions.get(t[0] as usize)?,
        *mesh.positions.get(t[1] as usize)?,
        *mesh.positions.get(t[2] as usize)?,
    ];
    p.iter().all(|q| q.is_finite()).then_some(p)
}

/// Fills the pixels whose centres lie inside the screen triangle `s` and are nearer than the
/// depth buffer with `shade(barycentrics)`, or with the wire colour within
/// [`WIRE_HALF_WIDTH`] of an edge when `wireframe` is set.
fn rasterise(
    image: &mut Image,
    depth: &mut [f64],
    s: [DVec3; 3],
    wireframe: bool,
    shade: impl Fn([f64; 3]) -> [u8; 3],
) {
    let area = edge(s[0], s[1], s[2]);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    let Some((x0, x1, y0, y1)) = pixel_bounds(s, image.width as f64, image.height as f64) else {
        return;
    };
    let inv = 1.0 / area;
    // Distance in pixels from the edge opposite corner i is b_i · |area| / |edge i|.
    let edge_scale = [(1, 2), (2, 0), (0, 1)]
        .map(|(a, b)| area.abs() / (s[b] - s[a]).truncate().length().max(1e-300));
    for y in y0..=y1 {
        for x in x0..=x1 {
            let p = DVec3::new(x as f64 + 0.5, y as f64 + 0.5, 0.0);
            let b = [
                edge(s[1], s[2], p) * inv,
                edge(s[2], s[0], p) * inv,
                edge(s[0], s[1], p) * inv,
            ];
            if b.iter().any(|&c| c < 0.0) {
                continue;
            }
            let z = b[0] * s[0].z + b[1] * s[1].z + b[2] * s[2].z;
            let i = y * image.width + x;
            if z > depth[i] {
                depth[i] = z;
                let on_edge = wireframe && (0..3).any(|k| b[k] * edge_scale[k] < WIRE_HALF_WIDTH);
                let color = if on_edge { WIRE } else { shade(b) };
                image.set(x as i64, y as i64, color);
            }
        }
    }
}

/// The inclusive pixel range covering the screen triangle, clipped to the image; `None` when
/// they do not meet.
fn pixel_bounds(s: [DVec3; 3], w: f64, h: f64) -> Option<(usize, usize, usize, usize)> {
    let min = |f: fn(&DVec3) -> f64| s.iter().map(f).fold(f64::INFINITY, f64::min);
    let max = |f: fn(&DVec3) -> f64| s.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
    let x0 = min(|p| p.x).floor().max(0.0);
    let x1 = max(|p| p.x).ceil().min(w - 1.0);
    let y0 = min(|p| p.y).floor().max(0.0);
    let y1 = max(|p| p.y).ceil().min(h - 1.0);
    (x0 <= x1 && y0 <= y1).then_some((x0 as usize, x1 as usize, y0 as usize, y1 as usize))
}

#[inline]
fn edge(a: DVec3, b: DVec3, p: DVec3) -> f64 {
    (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)
}
