//! The detail spectrum: how much detail each band of levels carries.
//!
//! Bands are octaves of levels, `(2^k, 2^(k+1)]` clipped to the pyramid's levels, so each band
//! doubles the resolution of the one before — the mesh analogue of a frequency octave. For
//! each band: the number of levels and details, the energy `Σ |d|²` relative to the squared
//! bounding-box diagonal, and the RMS detail length relative to the diagonal.

use super::DetailPyramid;
use super::gains::feature_size_of_level;
use std::fmt::Write;

/// The detail energy of one band of levels `(lo, hi]`.
#[derive(Clone, Debug, PartialEq)]
pub struct BandEnergy {
    /// Lower level (exclusive).
    pub lo: usize,
    /// Upper level (inclusive).
    pub hi: usize,
    /// Number of levels (vertex splits) in the band.
    pub levels: usize,
    /// Number of detail vectors in the band.
    pub details: usize,
    /// `Σ |d|² / diagonal²` over the band's details.
    pub energy: f64,
    /// `sqrt(Σ |d|² / details) / diagonal`.
    pub rms: f64,
    /// Typical edge length at level `hi` (model units).
    pub feature_size: f64,
}

/// Detail energy per octave band of levels, coarse to fine.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectrum {
    /// The bands, coarse to fine.
    pub bands: Vec<BandEnergy>,
}

impl DetailPyramid {
    /// The detail spectrum of the pyramid (octave bands).
    pub fn spectrum(&self) -> Spectrum {
        octave_spectrum(
            self.n_base,
            self.n_finest,
            self.surface_area,
            self.bbox_diagonal,
            (0..self.n_splits()).map(|k| self.split_details(k).1),
        )
    }
}

/// The octave bands `(lo, hi]` of a hierarchy from `n_base` to `n_finest` vertices, coarse to
/// fine: the bands of [`octave_spectrum`], from the level counts alone.
pub(crate) fn octave_bands(n_base: usize, n_finest: usize) -> Vec<(usize, usize)> {
    let mut bands = Vec::new();
    let mut level = n_base + 1;
    while level <= n_finest {
        let hi = level.next_power_of_two();
        bands.push(((hi / 2).max(n_base), hi.min(n_finest)));
        level = hi + 1;
    }
    bands
}

/// The spectrum of the details of each split in split order (`per_split`), on a hierarchy from
/// `n_base` to `n_finest` vertices whose finest mesh has area `surface_area` and bounding-box
/// diagonal `diagonal`.
pub(crate) fn octave_spectrum<D: ExactSizeIterator<Item = glam::DVec3>>(
    n_base: usize,
    n_finest: usize,
    surface_area: f64,
    diagonal: f64,
    per_split: impl Iterator<Item = D>,
) -> Spectrum {
    let mut bands: Vec<BandEnergy> = Vec::new();
    let mut sums: Vec<f64> = Vec::new();
    for (k, details) in per_split.enumerate() {
        let level = n_base + k + 1;
        // Octave (2^b, 2^(b+1)] holding `level`.
        let hi = (level).next_power_of_two();
        let lo = (hi / 2).max(n_base);
        if bands.last().is_none_or(|b| b.hi != hi.min(n_finest)) {
            bands.push(empty_band(lo, hi.min(n_finest), surface_area));
            sums.push(0.0);
        }
        let band = bands.last_mut().expect("pushed above");
        band.levels += 1;
        band.details += details.len();
        let sum = sums.last_mut().expect("pushed above");
        for d in details {
            *sum += d.length_squared();
        }
    }
    with_energies(bands, &sums, diagonal)
}

/// [`octave_spectrum`] from the detail counts of each split (`counts`, in split order) and
/// each band's `Σ |d|²` (`band_sums`, coarse to fine, one per band of [`octave_bands`]):
/// when those sums are the exact ones, the same bits as [`octave_spectrum`] on the details.
pub(crate) fn octave_spectrum_of_sums(
    n_base: usize,
    n_finest: usize,
    surface_area: f64,
    diagonal: f64,
    counts: &[u32],
    band_sums: &[f64],
) -> Spectrum {
    let bands = octave_bands(n_base, n_finest)
        .into_iter()
        .map(|(lo, hi)| {
            let mut band = empty_band(lo, hi, surface_area);
            band.levels = hi - lo;
            band.details = counts[lo - n_base..hi - n_base]
                .iter()
                .map(|&c| c as usize)
                .sum();
            band
        })
        .collect();
    with_energies(bands, band_sums, diagonal)
}

fn empty_band(lo: usize, hi: usize, surface_area: f64) -> BandEnergy {
    BandEnergy {
        lo,
        hi,
        levels: 0,
        details: 0,
        energy: 0.0,
        rms: 0.0,
        feature_size: feature_size_of_level(hi, surface_area),
    }
}

/// The bands with their energies and RMS lengths from each band's `Σ |d|²` (`sums`).
fn with_energies(mut bands: Vec<BandEnergy>, sums: &[f64], diagonal: f64) -> Spectrum {
    let diag2 = (diagonal * diagonal).max(f64::MIN_POSITIVE);
    for (b, &s) in bands.iter_mut().zip(sums) {
        b.energy = s / diag2;
        b.rms = if b.details > 0 {
            (s / b.details as f64).sqrt() / diag2.sqrt()
        } else {
            0.0
        };
    }
    Spectrum { bands }
}

impl Spectrum {
    /// The table as CSV with a header line.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "level_from,level_to,levels,details,energy_rel_diag2,rms_rel_diag,feature_size\n",
        );
        for b in &self.bands {
            let _ = writeln!(
                s,
                "{},{},{},{},{:e},{:e},{:e}",
                b.lo, b.hi, b.levels, b.details, b.energy, b.rms, b.feature_size
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octave_bands_from_the_counts_are_the_spectrum_bands() {
        let cases = [
            (4, 4),
            (4, 5),
            (1, 2),
            (3, 100),
            (8, 8193),
            (16, 1024),
            (5, 1025),
            (7, 64),
        ];
        for (n_base, n_finest) in cases {
            let per_split = (n_base..n_finest).map(|_| std::iter::empty::<glam::DVec3>());
            let spectrum = octave_spectrum(n_base, n_finest, 1.0, 1.0, per_split);
            let bands: Vec<_> = spectrum.bands.iter().map(|b| (b.lo, b.hi)).collect();
            assert_eq!(
                octave_bands(n_base, n_finest),
                bands,
                "{n_base}..{n_finest}"
            );
        }
    }
}
