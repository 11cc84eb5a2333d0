//! Log-scale bar charts drawn pixel by pixel, with an embedded 5×7 bitmap font.
//!
//! Used for the detail spectrum (`meshpyr spectrum`). Hand-drawn rather than plotters because a
//! bar chart with decade grid lines needs only rectangles and short labels: this keeps the
//! binary free of a vendored 740 KB TrueType font and of plotters' stale dependency tree, and
//! makes the PNG byte-identical everywhere (no font rasteriser, no anti-aliasing differences).

use meshpyr::Spectrum;
use meshpyr::render::{Image, font};

/// One data series: a value per category (non-positive values are not drawn on a log axis).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Series {
    /// Legend text.
    pub name: String,
    /// One value per category.
    pub values: Vec<f64>,
    /// Bar colour.
    pub color: [u8; 3],
}

/// A bar chart with a logarithmic y axis; categories are drawn left to right, the series of one
/// category side by side.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BarChart {
    /// Title above the plot.
    pub title: String,
    /// Label under the x axis.
    pub x_label: String,
    /// Label above the y axis.
    pub y_label: String,
    /// One short label per category.
    pub categories: Vec<String>,
    /// The data.
    pub series: Vec<Series>,
    /// Image width in pixels (default 960).
    pub width: usize,
    /// Image height in pixels (default 540).
    pub height: usize,
}

/// Colours for successive series.
pub(crate) const PALETTE: [[u8; 3]; 4] = [[52, 101, 164], [204, 0, 0], [78, 154, 6], [245, 121, 0]];

const INK: [u8; 3] = [30, 30, 30];
const GRID: [u8; 3] = [215, 215, 215];
const TEXT_SCALE: i64 = 2;

impl BarChart {
    /// A chart with the default size.
    pub(crate) fn new(
        title: &str,
        x_label: &str,
        y_label: &str,
        categories: Vec<String>,
    ) -> BarChart {
        BarChart {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            categories,
            series: Vec::new(),
            width: 960,
            height: 540,
        }
    }

    /// Draws the chart.
    pub(crate) fn draw(&self) -> Image {
        let (w, h) = (self.width.max(200) as i64, self.height.max(150) as i64);
        let mut img = Image::new(w as usize, h as usize, [255, 255, 255]);
        let (left, right, top, bottom) = (100i64, w - 20, 60i64, h - 70);
        draw_text(&mut img, &self.title, left, 12, INK);
        draw_text(&mut img, &self.y_label, 10, 36, INK);
        let xl = text_width(&self.x_label);
        draw_text(
            &mut img,
            &self.x_label,
            (left + right - xl) / 2,
            h - 24,
            INK,
        );

        // Decade range covering all positive values.
        let positive = self
            .series
            .iter()
            .flat_map(|s| s.values.iter().copied())
            .filter(|v| *v > 0.0 && v.is_finite());
        let (lo, hi) = positive.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let (d0, d1) = if lo <= hi {
            let d0 = lo.log10().floor() as i32;
            let d1 = (hi.log10().ceil() as i32).max(d0 + 1);
            (d0, d1)
        } else {
            (0, 1)
        };
        let y_of = |v: f64| -> i64 {
            let t = (v.log10() - d0 as f64) / (d1 - d0) as f64;
            bottom - (t * (bottom - top) as f64).round() as i64
        };
        let step = ((d1 - d0) as usize).div_ceil(10).max(1);
        for d in (d0..=d1).step_by(step) {
            let y = y_of(10f64.powi(d));
            img.fill_rect(left, y, right, y + 1, GRID);
            let label = format!("1E{d}");
            draw_text(&mut img, &label, left - 8 - text_width(&label), y - 7, INK);
        }

        // Bars.
        let nc = self.categories.len().max(1) as i64;
        let ns = self.series.len().max(1) as i64;
        let slot = (right - left) / nc;
        let bar = ((slot * 3 / 4) / ns).max(1);
        for (c, label) in self.categories.iter().enumerate() {
            let x0 = left + c as i64 * slot + (slot - bar * ns) / 2;
            for (k, s) in self.series.iter().enumerate() {
                if let Some(&v) = s.values.get(c)
                    && v > 0.0
                    && v.is_finite()
                {
                    let xb = x0 + k as i64 * bar;
                    img.fill_rect(xb, y_of(v), xb + bar, bottom, s.color);
                }
            }
            let lw = text_width(label);
            let xc = left + c as i64 * slot + slot / 2;
            draw_text(&mut img, label, xc - lw / 2, bottom + 8, INK);
        }

        // Axes and legend.
        img.fill_rect(left, top, left + 2, bottom + 1, INK);
        img.fill_rect(left, bottom, right, bottom + 2, INK);
        let mut y = top;
        for s in &self.series {
            let x = right - 20 - text_width(&s.name) - 22;
            img.fill_rect(x, y, x + 14, y + 14, s.color);
            draw_text(&mut img, &s.name, x + 22, y, INK);
            y += 22;
        }
        img
    }
}

/// Width in pixels of `text` at the chart's text scale.
pub(crate) fn text_width(text: &str) -> i64 {
    font::text_width(text, TEXT_SCALE)
}

/// Draws `text` at the chart's text scale with its top-left corner at `(x, y)`.
pub(crate) fn draw_text(img: &mut Image, text: &str, x: i64, y: i64, color: [u8; 3]) {
    font::draw_text(img, text, x, y, color, TEXT_SCALE);
}

/// A compact count label: `950`, `1.5K`, `16K`, `1.2M`.
pub(crate) fn compact_count(n: usize) -> String {
    let f = n as f64;
    let (v, unit) = if n >= 1_000_000 {
        (f / 1e6, "M")
    } else if n >= 1000 {
        (f / 1e3, "K")
    } else {
        return n.to_string();
    };
    if v < 10.0 && (v * 10.0).round() % 10.0 != 0.0 {
        format!("{v:.1}{unit}")
    } else {
        format!("{}{unit}", v.round())
    }
}

/// A bar chart of the energies of `spectrum` and of `others` (same bands expected, e.g.
/// the spectra of filtered versions), each series named.
pub(crate) fn spectrum_chart(
    spectrum: &Spectrum,
    name: &str,
    others: &[(&str, &Spectrum)],
) -> Image {
    let categories = spectrum.bands.iter().map(|b| compact_count(b.hi)).collect();
    let mut c = BarChart::new(
        "DETAIL SPECTRUM: ENERGY PER LEVEL OCTAVE",
        "LEVEL (VERTICES, UPPER END OF OCTAVE)",
        "SUM |D|^2 / DIAG^2",
        categories,
    );
    let all = std::iter::once((name, spectrum)).chain(others.iter().copied());
    for (i, (n, s)) in all.enumerate() {
        c.series.push(Series {
            name: n.to_string(),
            values: spectrum
                .bands
                .iter()
                .map(|b| {
                    s.bands
                        .iter()
                        .find(|o| o.hi == b.hi)
                        .map_or(0.0, |o| o.energy)
                })
                .collect(),
            color: PALETTE[i % PALETTE.len()],
        });
    }
    c.draw()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chart() -> BarChart {
        let mut c = BarChart::new(
            "Detail spectrum",
            "level (vertices)",
            "energy",
            vec!["64".into(), "128".into(), "256".into()],
        );
        c.series.push(Series {
            name: "input".into(),
            values: vec![1e-2, 1e-4, 3e-6],
            color: PALETTE[0],
        });
        c.series.push(Series {
            name: "filtered".into(),
            values: vec![1e-2, 0.0, f64::NAN],
            color: PALETTE[1],
        });
        c
    }

    fn count(img: &Image, color: [u8; 3]) -> usize {
        img.rgb.chunks(3).filter(|p| *p == color).count()
    }

    #[test]
    fn bars_are_proportional_to_log_values_and_missing_ones_are_skipped() {
        let c = chart();
        let img = c.draw();
        // Range 1e-6 .. 1e-2: four decades over the plot height.
        let blue = count(&img, PALETTE[0]);
        let red = count(&img, PALETTE[1]);
        assert!(blue > red && red > 0);
        // Tallest column of each colour: the first bars both hold 1e-2, the top of the range.
        let tallest = |color: [u8; 3]| {
            (0..img.width)
                .map(|x| {
                    (0..img.height)
                        .filter(|&y| img.pixel(x, y) == Some(color))
                        .count()
                })
                .max()
                .unwrap_or(0)
        };
        assert_eq!(tallest(PALETTE[0]), tallest(PALETTE[1]));
        // Four decades over 540 − 130 = 410 rows: 1e-2 spans all of them, 1e-4 half.
        assert_eq!(tallest(PALETTE[0]), 410);
        let _ = c;
    }

    #[test]
    fn chart_png_is_byte_identical_across_runs() {
        let a = chart().draw().encode_png().unwrap();
        let b = chart().draw().encode_png().unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn text_draws_known_glyph_pixels() {
        let mut img = Image::new(20, 20, [255; 3]);
        draw_text(&mut img, "1", 0, 0, [0; 3]);
        // '1' has 1+2+1+1+1+1+3 = 10 lit cells of 2×2 pixels.
        assert_eq!(count(&img, [0; 3]), 10 * 4);
        let mut blank = Image::new(20, 20, [255; 3]);
        draw_text(&mut blank, "€ ", 0, 0, [0; 3]);
        assert_eq!(count(&blank, [0; 3]), 0);
    }

    #[test]
    fn compact_counts() {
        assert_eq!(compact_count(950), "950");
        assert_eq!(compact_count(1000), "1K");
        assert_eq!(compact_count(1500), "1.5K");
        assert_eq!(compact_count(16384), "16K");
        assert_eq!(compact_count(1_200_000), "1.2M");
    }
}
