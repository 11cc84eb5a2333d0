//! Pictures of several panels: the meshes side by side under one camera, a caption above each,
//! and a colour bar with its range under them when the panels carry values.

use super::font::{draw_text, text_height, text_width};
use super::raster::{Camera, Paint, PanelTexture, draw_panel};
use super::{Image, RenderOptions, Triangles};

/// Colour of captions and colour-bar text.
const INK: [u8; 3] = [30, 30, 30];

/// One panel of a picture.
#[derive(Clone, Copy, Debug)]
pub struct Panel<'a> {
    /// The triangles to draw.
    pub mesh: Triangles<'a>,
    /// Caption above the panel when there are several (none when empty), shortened from the
    /// left to fit; also names the mesh in errors.
    pub label: &'a str,
    /// One value per vertex to colour the surface by (missing or non-finite values are grey).
    pub values: Option<&'a [f64]>,
    /// The images and texture coordinates of a textured mesh (ignored where `values` colour
    /// the surface).
    pub texture: Option<PanelTexture<'a>>,
}

/// Draws the panels left to right with one shared camera, so equal sizes look equal. When
/// there are several panels and any has a label, a caption strip runs above them (a lone
/// panel goes without); when any has values, a colour bar
/// under them shows the colour range (`options.range`, or the values' finite minimum and
/// maximum over all panels) with its ends printed and `options.color_by` (or "value") as its
/// title. Each panel is `options.width × options.height`; the strips add to the height.
pub fn render_scene(panels: &[Panel<'_>], options: &RenderOptions) -> Image {
    let meshes: Vec<Triangles<'_>> = panels.iter().map(|p| p.mesh).collect();
    let camera = Camera::fit(&meshes, options);
    let range = options.range.unwrap_or_else(|| value_range(panels));
    let layout = Layout::new(panels, options);
    let mut out = Image::new(layout.width, layout.height, options.background);
    for (k, panel) in panels.iter().enumerate() {
        let paint = Paint {
            values: panel.values,
            range,
            texture: panel.texture,
        };
        let image = draw_panel(panel.mesh, &paint, &camera, options);
        let x = (k * layout.panel_width) as i64;
        out.blit(&image, x, layout.caption_height);
        if layout.caption_height > 0 {
            draw_caption(&mut out, panel.label, x, &layout);
        }
    }
    if layout.bar_height > 0 {
        let title = options.color_by.as_deref().unwrap_or("value");
        draw_color_bar(&mut out, title, range, &layout);
    }
    out
}

/// Where the parts of a picture go.
struct Layout {
    width: usize,
    height: usize,
    panel_width: usize,
    panel_height: usize,
    caption_height: i64,
    bar_height: i64,
    text_scale: i64,
}

impl Layout {
    fn new(panels: &[Panel<'_>], options: &RenderOptions) -> Layout {
        let (w, h) = (options.width.max(1), options.height.max(1));
        // Large text where it fits comfortably, small text on thumbnails.
        let text_scale = if w >= 240 { 2 } else { 1 };
        let line = text_height(text_scale) + 6 * text_scale;
        // Captions tell panels apart; a lone panel goes without.
        let caption_height = if panels.len() > 1 && panels.iter().any(|p| !p.label.is_empty()) {
            line
        } else {
            0
        };
        // Title line, bar, range line.
        let bar_height = if panels.iter().any(|p| p.values.is_some()) {
            2 * line + 8 * text_scale
        } else {
            0
        };
        Layout {
            width: w * panels.len().max(1),
            height: h + (caption_height + bar_height) as usize,
            panel_width: w,
            panel_height: h,
            caption_height,
            bar_height,
            text_scale,
        }
    }
}

/// The finite minimum and maximum of all panels' values, `(0, 1)` when there are none.
fn value_range(panels: &[Panel<'_>]) -> (f64, f64) {
    let finite = panels
        .iter()
        .filter_map(|p| p.values)
        .flatten()
        .copied()
        .filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if lo <= hi { (lo, hi) } else { (0.0, 1.0) }
}

/// Centres `label` over the panel starting at `x`, cut from the left (`..` prefix) to fit.
fn draw_caption(out: &mut Image, label: &str, x: i64, layout: &Layout) {
    if label.is_empty() {
        return;
    }
    let scale = layout.text_scale;
    let room = layout.panel_width as i64 - 4 * scale;
    let text = fit_from_left(label, room, scale);
    let left = x + (layout.panel_width as i64 - text_width(&text, scale)) / 2;
    draw_text(out, &text, left, 3 * scale, INK, scale);
}

/// `text`, or its end behind `..`, whichever fits in `room` pixels.
fn fit_from_left(text: &str, room: i64, scale: i64) -> String {
    if text_width(text, scale) <= room {
        return text.to_string();
    }
    let chars: Vec<char> = text.chars().collect();
    let keep = (room / text_width("x", scale) - 2).max(0) as usize;
    let tail: String = chars[chars.len().saturating_sub(keep)..].iter().collect();
    format!("..{tail}")
}

/// The title, a horizontal bar through the colour map, and the range's ends under its ends.
fn draw_color_bar(out: &mut Image, title: &str, (lo, hi): (f64, f64), layout: &Layout) {
    let scale = layout.text_scale;
    let line = text_height(scale) + 6 * scale;
    let top = layout.caption_height + layout.panel_height as i64;
    let (x0, x1) = (8 * scale, out.width as i64 - 8 * scale);
    let title = fit_from_left(title, x1 - x0, scale);
    let title_x = (out.width as i64 - text_width(&title, scale)) / 2;
    draw_text(out, &title, title_x, top + 3 * scale, INK, scale);
    let (bar_top, bar_bottom) = (top + line, top + line + 8 * scale);
    let span = (x1 - x0 - 1).max(1) as f64;
    for x in x0..x1 {
        let color = super::colormap::colormap((x - x0) as f64 / span);
        out.fill_rect(x, bar_top, x + 1, bar_bottom, color);
    }
    let (low, high) = (format_value(lo), format_value(hi));
    let y = bar_bottom + 3 * scale;
    draw_text(out, &low, x0, y, INK, scale);
    draw_text(out, &high, x1 - text_width(&high, scale), y, INK, scale);
}

/// A short, exact-enough label: four significant digits, in exponent form outside
/// `[0.001, 10000)`.
pub(crate) fn format_value(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".to_string()
    } else if (1e-3..1e4).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_print_with_four_significant_digits() {
        assert_eq!(format_value(0.0), "0");
        assert_eq!(format_value(0.012345), "0.01235");
        assert_eq!(format_value(1.5), "1.500");
        assert_eq!(format_value(-250.0), "-250.0");
        assert_eq!(format_value(2.5e-5), "2.500e-5");
        assert_eq!(format_value(123456.0), "1.235e5");
    }

    #[test]
    fn long_captions_keep_their_end() {
        assert_eq!(fit_from_left("short.ply", 100, 1), "short.ply");
        // 60 pixels hold ten cells: two dots and the last eight characters.
        assert_eq!(fit_from_left("a-very-long-name.ply", 60, 1), "..name.ply");
    }
}
