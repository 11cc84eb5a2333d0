//! The images of a textured mesh's materials, decoded for drawing, and how a point of the
//! surface takes its colour from them.
//!
//! Steps: [`Textures::load`] reads each material's diffuse image (OBJ `map_Kd`, PLY
//! `TextureFile`) once per file, relative to the folder the mesh was read from, and decodes it
//! ([`decode_image`]: PNG in any bit depth and colour type, or JPEG, reduced to 8-bit RGB). The
//! rasteriser then interpolates the per-corner texture coordinates of each triangle at the pixel
//! and samples the image there ([`sample`]): bilinear between the four nearest texel centres,
//! the coordinates wrapping (repeat), as OBJ and GPU samplers read them. `v` runs upwards, so
//! `v = 0` is the image's bottom row. The pictures are orthographic, so the screen's
//! barycentric coordinates are those of the triangle itself and the linear interpolation is
//! perspective-correct.
//!
//! A missing or undecodable image is a warning naming it: its faces are drawn in the plain
//! surface colour, as are faces of a material without an image.

use std::path::Path;
use std::sync::Arc;

use super::Image;
use crate::mesh::PolygonMesh;

/// Largest image side decoded: larger files are refused before their pixels are allocated.
const MAX_SIDE: u32 = 16_384;

/// The decoded diffuse images of a mesh's materials.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Textures {
    /// One entry per material (as [`Materials::list`](crate::mesh::Materials::list) orders
    /// them): its image, or `None` when it has none or it could not be read. Materials naming
    /// the same file share one decoded image.
    pub images: Vec<Option<Arc<Image>>>,
}

impl Textures {
    /// Reads and decodes the images `mesh`'s materials name, relative to the folder it was read
    /// from ([`Materials::folder`](crate::mesh::Materials::folder); a mesh not read from a file
    /// resolves them from the working directory). Returns the images and one warning per image
    /// that is missing or cannot be decoded, naming it.
    pub fn load(mesh: &PolygonMesh) -> (Textures, Vec<String>) {
        let folder = mesh.materials.folder.as_deref().unwrap_or(Path::new(""));
        let mut read: Vec<(&str, Option<Arc<Image>>)> = Vec::new();
        let mut warnings = Vec::new();
        let mut images = Vec::with_capacity(mesh.materials.list.len());
        for material in &mesh.materials.list {
            let Some(name) = material.texture.as_deref() else {
                images.push(None);
                continue;
            };
            if let Some((_, image)) = read.iter().find(|(n, _)| *n == name) {
                images.push(image.clone());
                continue;
            }
            let image = match std::fs::read(folder.join(name)) {
                Ok(bytes) => decode_image(&bytes)
                    .map_err(|e| {
                        warnings.push(format!(
                            "image {name} cannot be decoded ({e}); its faces are drawn without it"
                        ))
                    })
                    .ok()
                    .map(Arc::new),
                Err(e) => {
                    warnings.push(format!(
                        "image {name} cannot be read ({e}); its faces are drawn without it"
                    ));
                    None
                }
            };
            read.push((name, image.clone()));
            images.push(image);
        }
        (Textures { images }, warnings)
    }

    /// True when no material has an image.
    pub fn is_empty(&self) -> bool {
        self.images.iter().all(Option::is_none)
    }

    /// The image of material `material`, if it has one.
    pub fn image(&self, material: usize) -> Option<&Image> {
        self.images.get(material)?.as_deref()
    }
}

/// Decodes a PNG file of any bit depth and colour type, or a baseline or progressive JPEG
/// file, to 8-bit RGB (grey is spread to the three channels, alpha dropped); a one-line error
/// otherwise.
pub fn decode_image(bytes: &[u8]) -> Result<Image, String> {
    if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        return decode_jpeg(bytes);
    }
    if !bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        return Err("neither a PNG nor a JPEG file".into());
    }
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let header = decoder.read_header_info().map_err(|e| e.to_string())?;
    let (w, h) = (header.width, header.height);
    if w > MAX_SIDE || h > MAX_SIDE {
        return Err(format!("{w}×{h} pixels, over {MAX_SIDE} on a side"));
    }
    decoder.set_limits(png::Limits {
        bytes: 8 * w as usize * h as usize + (1 << 20),
    });
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let size = reader
        .output_buffer_size()
        .ok_or("the image is too large to decode")?;
    let mut buf = vec![0u8; size];
    let frame = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    let channels = frame.color_type.samples();
    let (width, height) = (frame.width as usize, frame.height as usize);
    let mut rgb = Vec::with_capacity(3 * width * height);
    for row in buf.chunks_exact(frame.line_size).take(height) {
        for px in row.chunks_exact(channels).take(width) {
            match channels {
                1 | 2 => rgb.extend_from_slice(&[px[0]; 3]),
                _ => rgb.extend_from_slice(&px[..3]),
            }
        }
    }
    if width == 0 || height == 0 || rgb.len() != 3 * width * height {
        return Err("the image has no pixels".into());
    }
    Ok(Image { width, height, rgb })
}

/// A JPEG file decoded to 8-bit RGB, refused past [`MAX_SIDE`] before its pixels are
/// allocated.
fn decode_jpeg(bytes: &[u8]) -> Result<Image, String> {
    let mut reader =
        image::ImageReader::with_format(std::io::Cursor::new(bytes), image::ImageFormat::Jpeg);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    limits.max_alloc = Some(8 * u64::from(MAX_SIDE) * u64::from(MAX_SIDE));
    reader.limits(limits);
    let rgb = reader.decode().map_err(|e| e.to_string())?.into_rgb8();
    let (width, height) = (rgb.width() as usize, rgb.height() as usize);
    if width == 0 || height == 0 {
        return Err("the image has no pixels".into());
    }
    Ok(Image {
        width,
        height,
        rgb: rgb.into_raw(),
    })
}

/// The colour of `image` at texture coordinates `(u, v)` (`v` upwards), bilinear between the
/// nearest texel centres, wrapping at the edges; channels in `[0, 255]`.
pub fn sample(image: &Image, u: f64, v: f64) -> [f64; 3] {
    let (w, h) = (image.width as i64, image.height as i64);
    let x = u * w as f64 - 0.5;
    let y = (1.0 - v) * h as f64 - 0.5;
    if !(x.is_finite() && y.is_finite()) {
        return [0.0; 3];
    }
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    // Reduced first, so that far-off coordinates cannot overflow the texel arithmetic.
    let (x0, y0) = (
        x0.rem_euclid(w as f64) as i64,
        y0.rem_euclid(h as f64) as i64,
    );
    let texel = |x: i64, y: i64| {
        let i = 3 * (y.rem_euclid(h) * w + x.rem_euclid(w)) as usize;
        [0, 1, 2].map(|c| f64::from(image.rgb[i + c]))
    };
    let (a, b) = (texel(x0, y0), texel(x0 + 1, y0));
    let (c, d) = (texel(x0, y0 + 1), texel(x0 + 1, y0 + 1));
    [0, 1, 2].map(|k| {
        let top = a[k] + fx * (b[k] - a[k]);
        let bottom = c[k] + fx * (d[k] - c[k]);
        top + fy * (bottom - top)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2×2 image: red, green on top; blue, white below.
    fn four() -> Image {
        Image {
            width: 2,
            height: 2,
            rgb: vec![255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255],
        }
    }

    #[test]
    fn texel_centres_give_their_colour_and_v_runs_upwards() {
        let image = four();
        assert_eq!(sample(&image, 0.25, 0.75), [255.0, 0.0, 0.0]);
        assert_eq!(sample(&image, 0.75, 0.75), [0.0, 255.0, 0.0]);
        assert_eq!(sample(&image, 0.25, 0.25), [0.0, 0.0, 255.0]);
        assert_eq!(sample(&image, 0.75, 0.25), [255.0; 3]);
    }

    #[test]
    fn between_centres_the_colours_blend_and_coordinates_wrap() {
        let image = four();
        assert_eq!(sample(&image, 0.5, 0.75), [127.5, 127.5, 0.0]);
        // u = 1 lies halfway between the last column and the first, wrapped round.
        assert_eq!(sample(&image, 1.0, 0.75), [127.5, 127.5, 0.0]);
        assert_eq!(sample(&image, 3.25, -1.25), sample(&image, 0.25, 0.75));
        assert_eq!(sample(&image, f64::NAN, 0.5), [0.0; 3]);
    }

    #[test]
    fn png_files_decode_to_rgb_and_other_bytes_are_refused() {
        let image = four();
        let back = decode_image(&image.encode_png().unwrap()).unwrap();
        assert_eq!(back, image);
        assert!(decode_image(b"\xff\xd8\xff\xe0 jfif").is_err());
        assert!(decode_image(b"hello").unwrap_err().contains("neither"));
        let png = image.encode_png().unwrap();
        assert!(decode_image(&png[..png.len() / 2]).is_err());
    }
}

#[cfg(test)]
mod jpeg_tests {
    use super::*;

    #[test]
    fn jpeg_files_decode_to_about_their_colours() {
        // Two 8×8 blocks side by side, red and blue: each a JPEG block, so the lossy code keeps
        // its colour to within a few levels.
        let mut rgb = Vec::new();
        for _y in 0..8 {
            for x in 0..16 {
                rgb.extend_from_slice(if x < 8 {
                    &[220, 30, 30]
                } else {
                    &[30, 30, 220]
                });
            }
        }
        let mut bytes = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 95)
            .encode(&rgb, 16, 8, image::ExtendedColorType::Rgb8)
            .unwrap();
        let image = decode_image(&bytes).unwrap();
        assert_eq!((image.width, image.height), (16, 8));
        let near = |a: [u8; 3], b: [u8; 3]| a.iter().zip(b).all(|(x, y)| x.abs_diff(y) <= 12);
        assert!(
            near(image.pixel(3, 4).unwrap(), [220, 30, 30]),
            "{:?}",
            image.pixel(3, 4)
        );
        assert!(
            near(image.pixel(12, 4).unwrap(), [30, 30, 220]),
            "{:?}",
            image.pixel(12, 4)
        );
        assert!(decode_image(&bytes[..bytes.len() / 3]).is_err());
    }
}
