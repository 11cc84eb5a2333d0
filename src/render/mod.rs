//! Deterministic software pictures of meshes: an orthographic z-buffer rasteriser with flat or
//! smooth Lambert shading, an optional wireframe, colour by a per-vertex value with a colour
//! bar or by the images of a textured mesh ([`Textures`]), captions, and a small RGB image type
//! that encodes to PNG.
//!
//! No GPU, no threads, no font or system library: the same triangles and options always give a
//! byte-identical PNG, which is what the tests and the demo rely on. Several meshes can be drawn
//! side by side with one shared camera (fitted to the union of their bounding boxes), so the
//! panels are comparable at a glance.
//!
//! [`render_mesh`] and [`render_meshes`] draw [`PolygonMesh`](crate::PolygonMesh)es,
//! [`render_textured_meshes`] with their textures (what `meshpyr render` does);
//! [`render_scene`] draws triangle soups with captions and values.

mod colormap;
pub mod font;
mod polygon;
mod raster;
mod scene;
mod texture;

pub use polygon::{RenderError, render_mesh, render_meshes, render_textured_meshes};
pub use raster::{NO_IMAGE, PanelTexture};
pub use scene::{Panel, render_scene};
pub use texture::{Textures, decode_image, sample};

use glam::DVec3;

/// Error while encoding an image.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The PNG encoder failed (only possible for absurd sizes).
    #[error("PNG encoding failed: {0}")]
    Png(#[from] png::EncodingError),
    /// Width or height is zero or too large to encode.
    #[error("image size {width}×{height} cannot be encoded")]
    Size {
        /// Requested width in pixels.
        width: usize,
        /// Requested height in pixels.
        height: usize,
    },
}

/// An 8-bit RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `3 · width · height` bytes, row-major.
    pub rgb: Vec<u8>,
}

impl Image {
    /// An image filled with `color`.
    pub fn new(width: usize, height: usize, color: [u8; 3]) -> Image {
        let mut rgb = Vec::with_capacity(3 * width * height);
        for _ in 0..width * height {
            rgb.extend_from_slice(&color);
        }
        Image { width, height, rgb }
    }

    /// The colour at `(x, y)`, or `None` outside the image.
    pub fn pixel(&self, x: usize, y: usize) -> Option<[u8; 3]> {
        (x < self.width && y < self.height).then(|| {
            let i = 3 * (y * self.width + x);
            [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
        })
    }

    /// Sets `(x, y)` to `color`; pixels outside the image are ignored.
    #[inline]
    pub fn set(&mut self, x: i64, y: i64, color: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let i = 3 * (y as usize * self.width + x as usize);
            self.rgb[i..i + 3].copy_from_slice(&color);
        }
    }

    /// Fills the rectangle `[x0, x1) × [y0, y1)` (clipped to the image).
    pub fn fill_rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, color: [u8; 3]) {
        let (xa, xb) = (x0.max(0), x1.min(self.width as i64));
        let (ya, yb) = (y0.max(0), y1.min(self.height as i64));
        for y in ya..yb {
            for x in xa..xb {
                self.set(x, y, color);
            }
        }
    }

    /// Copies `other` into this image with its top-left corner at `(x, y)` (clipped).
    pub(crate) fn blit(&mut self, other: &Image, x: i64, y: i64) {
        for oy in 0..other.height {
            for ox in 0..other.width {
                let i = 3 * (oy * other.width + ox);
                let c = [other.rgb[i], other.rgb[i + 1], other.rgb[i + 2]];
                self.set(x + ox as i64, y + oy as i64, c);
            }
        }
    }

    /// Encodes as an 8-bit RGB PNG. Deterministic: no timestamps or text chunks.
    pub fn encode_png(&self) -> Result<Vec<u8>, ImageError> {
        let size_error = ImageError::Size {
            width: self.width,
            height: self.height,
        };
        let (Ok(w), Ok(h)) = (u32::try_from(self.width), u32::try_from(self.height)) else {
            return Err(size_error);
        };
        if w == 0 || h == 0 || self.rgb.len() != 3 * self.width * self.height {
            return Err(size_error);
        }
        let mut bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut bytes, w, h);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_compression(png::Compression::Balanced);
            let mut writer = encoder.write_header()?;
            writer.write_image_data(&self.rgb)?;
            writer.finish()?;
        }
        Ok(bytes)
    }
}

/// How previews are drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Width of one panel in pixels (default 480).
    pub width: usize,
    /// Height of one panel in pixels (default 480).
    pub height: usize,
    /// Rotation of the model about the vertical (y) axis before viewing along −z, in degrees
    /// (default 0: the model's +z faces the viewer).
    pub yaw_degrees: f64,
    /// Rotation about the horizontal (x) axis after the yaw, in degrees (default 0).
    pub pitch_degrees: f64,
    /// Fraction of the panel left empty around the model on each side (default 0.05).
    pub margin: f64,
    /// Background colour (default white).
    pub background: [u8; 3],
    /// Surface colour at full light (default a light clay).
    pub color: [u8; 3],
    /// Direction *towards* the light in view space (x right, y up, z towards the viewer);
    /// normalised internally (default upper left front).
    pub light: DVec3,
    /// Ambient fraction of the surface colour, in `[0, 1]` (default 0.18).
    pub ambient: f64,
    /// Flat (one normal per triangle, the default) or smooth (interpolated vertex normals).
    pub shading: Shading,
    /// Draws the triangle edges over the surface (default off).
    pub wireframe: bool,
    /// The per-vertex attribute that colours the surface ([`render_meshes`]), and the colour
    /// bar's title (default none: the plain surface colour).
    pub color_by: Option<String>,
    /// The values mapped to the ends of the colour map, `(min, max)`; values outside are
    /// clamped (default: the values' own minimum and maximum over all panels).
    pub range: Option<(f64, f64)>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 480,
            height: 480,
            yaw_degrees: 0.0,
            pitch_degrees: 0.0,
            margin: 0.05,
            background: [255, 255, 255],
            color: [222, 205, 180],
            light: DVec3::new(-0.4, 0.6, 1.0),
            ambient: 0.18,
            shading: Shading::Flat,
            wireframe: false,
            color_by: None,
            range: None,
        }
    }
}

/// How the surface is shaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shading {
    /// One normal per triangle: facets visible, as the mesh really is.
    #[default]
    Flat,
    /// Vertex normals (area-weighted) interpolated across triangles: the look of the limit
    /// surface.
    Smooth,
}

/// A named viewing direction: which side of the model faces the viewer (y is up).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// +z towards the viewer.
    Front,
    /// −z towards the viewer.
    Back,
    /// −x towards the viewer.
    Left,
    /// +x towards the viewer.
    Right,
    /// +y towards the viewer.
    Top,
    /// −y towards the viewer.
    Bottom,
    /// From front right above, at equal angles to the three axes.
    Iso,
}

impl View {
    /// All views, in the order of their names in [`View::NAMES`].
    pub const ALL: [View; 7] = [
        View::Front,
        View::Back,
        View::Left,
        View::Right,
        View::Top,
        View::Bottom,
        View::Iso,
    ];
    /// The names [`View::from_str`](std::str::FromStr) accepts.
    pub const NAMES: [&'static str; 7] = ["front", "back", "left", "right", "top", "bottom", "iso"];

    /// `(yaw_degrees, pitch_degrees)` for [`RenderOptions`].
    pub fn angles(self) -> (f64, f64) {
        match self {
            View::Front => (0.0, 0.0),
            View::Back => (180.0, 0.0),
            View::Left => (90.0, 0.0),
            View::Right => (-90.0, 0.0),
            View::Top => (0.0, 90.0),
            View::Bottom => (0.0, -90.0),
            // The elevation at which the three axes appear at equal angles: atan(1/√2).
            View::Iso => (-45.0, (0.5f64).sqrt().atan().to_degrees()),
        }
    }
}

impl std::str::FromStr for View {
    type Err = String;

    fn from_str(s: &str) -> Result<View, String> {
        View::NAMES
            .iter()
            .position(|&n| n == s)
            .map(|k| View::ALL[k])
            .ok_or_else(|| format!("unknown view '{s}' (one of {})", View::NAMES.join(", ")))
    }
}

/// A triangle soup to draw: positions and index triples (indices out of range are skipped).
#[derive(Clone, Copy, Debug)]
pub struct Triangles<'a> {
    /// Vertex positions.
    pub positions: &'a [DVec3],
    /// Triangles as vertex indices.
    pub triangles: &'a [[u32; 3]],
}

/// Renders each mesh into its own panel, left to right, with one shared camera, without
/// captions or values ([`render_scene`] with bare panels).
pub fn render_panels(meshes: &[Triangles<'_>], options: &RenderOptions) -> Image {
    let panels: Vec<Panel<'_>> = meshes
        .iter()
        .map(|&mesh| Panel {
            mesh,
            label: "",
            values: None,
            texture: None,
        })
        .collect();
    render_scene(&panels, options)
}

/// Renders one mesh into a panel of `options.width × options.height`.
pub fn render(mesh: Triangles<'_>, options: &RenderOptions) -> Image {
    render_panels(&[mesh], options)
}

#[cfg(test)]
mod tests;
