//! Deterministic software pictures of meshes: an orthographic z-buffer rasteriser with flat or
//! smooth Lambert shading, an optional wireframe, colour by a per-vertex value with a colour
//! bar, captions, and a small RGB image type that encodes to PNG.
//!
//! No GPU, no threads, no font or system library: the same triangles and options always give a
//! byte-identical PNG, which is what the tests and the demo rely on. Several meshes can be drawn
//! side by side with one shared camera (fitted to the union of their bounding boxes), so the
//! panels are comparable at a glance.
//!
//! [`render_mesh`] and [`render_meshes`] draw [`PolygonMesh`](crate::PolygonMesh)es (what
//! `meshpyr render` does); [`render_scene`] draws triangle soups with captions and values.

mod colormap;
pub(crate) mod font;
mod polygon;
mod raster;
mod scene;

pub use polygon::{RenderError, render_mesh, render_meshes};
pub use scene::{Panel, render_scene};

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
    #[cfg(test)]
    pub(crate) fn pixel(&self, x: usize, y: usize) -> Option<[u8; 3]> {
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
    pub(crate) fn fill_rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, color: [u8; 3]) {
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
        })
        .collect();
    render_scene(&panels, options)
}

/// Renders one mesh into a panel of `options.width × options.height`.
pub fn render(mesh: Triangles<'_>, options: &RenderOptions) -> Image {
    render_panels(&[mesh], options)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (p, t)
    }

    #[test]
    fn cube_covers_the_centre_and_leaves_the_corners_empty() {
        let (p, t) = cube();
        let opts = RenderOptions {
            width: 64,
            height: 48,
            ..Default::default()
        };
        let img = render(
            Triangles {
                positions: &p,
                triangles: &t,
            },
            &opts,
        );
        assert_eq!((img.width, img.height), (64, 48));
        assert_ne!(img.pixel(32, 24), Some(opts.background));
        assert_eq!(img.pixel(0, 0), Some(opts.background));
        // Fitted to the height with a 5% margin: the square front face spans ~90% of 48 rows.
        let covered = (0..48)
            .filter(|&y| img.pixel(32, y) != Some(opts.background))
            .count();
        assert!((41..=45).contains(&covered), "{covered}");
    }

    #[test]
    fn nearer_faces_win_the_depth_test() {
        // Two overlapping squares at z = 0 (dark) and z = 1 (facing the light): the nearer one
        // must be visible whatever the drawing order.
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.2, 0.2, 1.0),
            DVec3::new(0.8, 0.2, 1.0),
            DVec3::new(0.5, 0.8, 1.0),
        ];
        let back = [[0, 1, 2], [0, 2, 3]];
        let front = [[4, 5, 6]];
        let opts = RenderOptions {
            width: 40,
            height: 40,
            color: [200, 0, 0],
            ..Default::default()
        };
        let order_a: Vec<[u32; 3]> = back.iter().chain(front.iter()).copied().collect();
        let order_b: Vec<[u32; 3]> = front.iter().chain(back.iter()).copied().collect();
        let a = render(
            Triangles {
                positions: &p,
                triangles: &order_a,
            },
            &opts,
        );
        let b = render(
            Triangles {
                positions: &p,
                triangles: &order_b,
            },
            &opts,
        );
        assert_eq!(a, b);
    }

    #[test]
    fn panels_share_a_camera_and_png_is_deterministic() {
        let (p, t) = cube();
        let small: Vec<DVec3> = p.iter().map(|&q| q * 0.5).collect();
        let opts = RenderOptions {
            width: 50,
            height: 50,
            yaw_degrees: 30.0,
            pitch_degrees: 20.0,
            ..Default::default()
        };
        let meshes = [
            Triangles {
                positions: &p,
                triangles: &t,
            },
            Triangles {
                positions: &small,
                triangles: &t,
            },
        ];
        let img = render_panels(&meshes, &opts);
        assert_eq!((img.width, img.height), (100, 50));
        let count = |x0: usize| {
            (0..50)
                .flat_map(|y| (x0..x0 + 50).map(move |x| (x, y)))
                .filter(|&(x, y)| img.pixel(x, y) != Some(opts.background))
                .count()
        };
        // Same camera: the half-size cube covers about a quarter of the pixels.
        let (big, half) = (count(0) as f64, count(50) as f64);
        assert!((half / big - 0.25).abs() < 0.06, "{big} {half}");
        let png1 = img.encode_png().unwrap();
        let png2 = render_panels(&meshes, &opts).encode_png().unwrap();
        assert_eq!(png1, png2);
        assert_eq!(&png1[1..4], b"PNG");
    }

    #[test]
    fn garbage_input_does_not_panic() {
        let p = vec![DVec3::splat(f64::NAN), DVec3::X, DVec3::Y];
        let t = vec![[0, 1, 2], [0, 1, 7], [1, 1, 2]];
        let img = render(
            Triangles {
                positions: &p,
                triangles: &t,
            },
            &RenderOptions::default(),
        );
        assert!(img.rgb.iter().all(|&c| c == 255));
        let empty = render(
            Triangles {
                positions: &[],
                triangles: &[],
            },
            &RenderOptions::default(),
        );
        assert_eq!(empty.width, 480);
        assert!(Image::new(0, 0, [0; 3]).encode_png().is_err());
    }
}
