//! Denoising on the detail pyramid with the normal-adaptive operator (`smooth --method pyramid`;
//! `docs/algorithms.md` §1e): the pyramid estimates the noise level itself and attenuates each
//! octave of levels by how much of it is noise.
//!
//! Steps:
//!
//! 1. **Pyramid.** The progressive mesh of the noisy mesh and its details under the
//!    normal-adaptive operator ([`analyze_with`]), whose predictions keep creases, so a
//!    crease costs small details and survives attenuation.
//! 2. **Noise response.** Analysis is linear and its weights come from the geometry alone, so
//!    analysing seeded white noise of unit deviation on the same hierarchy tells how large the
//!    details pure noise makes at each octave (`(n/2^(o+1), n/2^o]`); presmoothing averages it
//!    down towards coarse octaves.
//! 3. **Noise level.** The finest octave of a scan is mostly noise, so its median normal
//!    detail over the response's is the noise deviation `σ̂`; medians ignore the few large
//!    details of creases and corners.
//! 4. **Gains.** In octave `o` the ratio `r_o` of the median normal detail to `σ̂` times the
//!    response says how far the details stand above noise; the octave gets the Wiener gain
//!    `max(0, 1 − strength / r_o²)` (signal power over signal-plus-noise power). Fine octaves
//!    (`r ≈ 1`) vanish, octaves a few times above the noise keep most of their details.
//! 5. **Synthesis** with those gains.
//!
//! Per-octave gains rather than a threshold per detail: the pyramid is oversampled (about seven
//! details per vertex), and shrinking one split's details leaves the noise in the ring details
//! of the splits after it.

use super::{DetailPyramid, Filter, LevelSpec, analyze_with};
use crate::fairing::SmoothError;
use crate::mesh::Mesh;
use crate::pm::{PmOptions, ProgressiveMesh};
use crate::progress::{NoProgress, Progress};
use crate::relax::RelaxKind;
use glam::DVec3;

/// Options of [`pyramid_denoise`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PyramidDenoise {
    /// How much noise to assume, in units of the estimated noise power: octaves get the gain
    /// `max(0, 1 − strength / r²)`. 1 is the estimate itself; 2 removes more, 0.5 less, 0
    /// nothing.
    pub strength: f64,
}

impl Default for PyramidDenoise {
    fn default() -> Self {
        PyramidDenoise { strength: 1.0 }
    }
}

impl PyramidDenoise {
    /// Checks the option's range.
    pub fn validate(&self) -> Result<(), SmoothError> {
        if self.strength >= 0.0 && self.strength.is_finite() {
            Ok(())
        } else {
            Err(SmoothError::InvalidParameter(format!(
                "--strength must be a number at least 0, got {}",
                self.strength
            )))
        }
    }
}

/// What [`pyramid_denoise`] found and did.
#[derive(Clone, Debug, PartialEq)]
pub struct PyramidDenoised {
    /// New positions, indexed by vertex slot.
    pub positions: Vec<DVec3>,
    /// The estimated noise deviation along the normal, in model units.
    pub noise: f64,
    /// The gain of each octave, finest first.
    pub gains: Vec<f64>,
}

/// Denoises `mesh` on its detail pyramid (see the module docs); `progress` goes 0 → 1.
pub fn pyramid_denoise(
    mesh: &Mesh,
    options: &PyramidDenoise,
    progress: &dyn Progress,
) -> Result<PyramidDenoised, SmoothError> {
    options.validate()?;
    let failed = |e: &dyn std::fmt::Display| SmoothError::Pyramid(e.to_string());
    let pm = ProgressiveMesh::build(mesh, &PmOptions::default(), &|x: f64| {
        progress.update(0.3 * x)
    })
    .map_err(|e| failed(&e))?;
    let (relaxation, pyramid) = analyze_with(&RelaxKind::Normal.spec(), &pm, &|x: f64| {
        progress.update(0.3 + 0.5 * x)
    })
    .map_err(|e| failed(&e))?;
    let noise = white_noise(pm.original_positions().len(), NOISE_SEED);
    let response = DetailPyramid::analyze_signal(&pm, relaxation.as_ref(), &noise, &NoProgress)
        .map_err(|e| failed(&e))?;
    progress.update(0.9);
    let (signal, unit) = (octave_medians(&pyramid), octave_medians(&response));
    let sigma = match (signal.first(), unit.first()) {
        (Some(&s), Some(&u)) if u > 0.0 => s / u,
        _ => 0.0,
    };
    let gains = wiener_gains(&signal, &unit, sigma, options.strength);
    let filter = octave_filter(&gains, pyramid.n_vertices());
    let level_gains = filter.resolve(pyramid.surface_area());
    let mut positions = mesh.positions().to_vec();
    // Unit gains keep the input exactly, as `Pyramid::filter` does (synthesis would be within
    // the details' quantisation of it).
    if !level_gains.is_unit() {
        let filtered = pyramid.synthesize(&level_gains);
        for (&slot, &p) in pm.pm_to_mesh().iter().zip(&filtered) {
            positions[slot as usize] = p;
        }
    }
    progress.update(1.0);
    Ok(PyramidDenoised {
        positions,
        noise: sigma,
        gains,
    })
}

/// Seed of the white noise of step 2, so that the estimate is the same on every run.
const NOISE_SEED: u64 = 0x006d_6573_6870_7972;

/// The octave of `level` in a pyramid whose finest level is `finest`: 0 for `(finest/2,
/// finest]`, 1 for the half below, … Counted down from the finest level, not on the powers
/// of two of the spectrum's bands ([`DetailPyramid::levels_of_octaves`]), whose finest band
/// can hold a sliver of the levels: here the finest octave estimates the noise, so it always
/// holds half of them.
fn octave(level: usize, finest: usize) -> usize {
    let mut o = 0;
    let mut top = finest;
    while level * 2 <= top && top > 1 {
        top /= 2;
        o += 1;
    }
    o
}

/// Median length of the normal component of each split's new-vertex detail, per octave
/// (finest first).
fn octave_medians(pyramid: &DetailPyramid) -> Vec<f64> {
    let finest = pyramid.n_vertices();
    let mut octaves: Vec<Vec<f64>> = Vec::new();
    for k in 0..pyramid.n_splits() {
        let o = octave(pyramid.level_of_split(k), finest);
        if octaves.len() <= o {
            octaves.resize_with(o + 1, Vec::new);
        }
        if let Some(d) = pyramid.split_details(k).1.next() {
            octaves[o].push(d.z.abs());
        }
    }
    octaves.into_iter().map(median).collect()
}

fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Step 4: the gain of every octave; 1 where nothing is known (no noise, no response).
fn wiener_gains(signal: &[f64], unit: &[f64], sigma: f64, strength: f64) -> Vec<f64> {
    signal
        .iter()
        .zip(unit)
        .map(|(&s, &u)| {
            let noise = sigma * u;
            if noise > 0.0 && noise.is_finite() {
                let r = s / noise;
                (1.0 - strength / (r * r)).max(0.0)
            } else {
                1.0
            }
        })
        .collect()
}

/// A filter giving octave `o`, levels `(finest/2^(o+1), finest/2^o]`, the gain `gains[o]`.
fn octave_filter(gains: &[f64], finest: usize) -> Filter {
    let mut filter = Filter::default();
    for (o, &g) in gains.iter().enumerate() {
        let (hi, lo) = (finest >> o, finest >> (o + 1));
        if hi > lo && g != 1.0 {
            filter = filter.gain(LevelSpec::Vertices(lo), LevelSpec::Vertices(hi), g);
        }
    }
    filter
}

/// Seeded standard normal values (splitmix64 and the Box–Muller transform): the same on every
/// machine, with no dependency.
fn white_noise(n: usize, seed: u64) -> Vec<DVec3> {
    let mut state = seed;
    let mut uniform = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut normal = move || {
        let (u, v) = (uniform(), uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    (0..n)
        .map(|_| DVec3::new(normal(), normal(), normal()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A finely tessellated sphere of radius 1 with seeded noise of deviation `sigma` along
    /// the normal.
    fn noisy_sphere(sigma: f64) -> (Mesh, Vec<DVec3>) {
        let (clean, tris) = crate::mesh::shapes::icosphere(4);
        let bumps = white_noise(clean.len(), 11);
        let noisy: Vec<DVec3> = clean
            .iter()
            .zip(&bumps)
            .map(|(&p, b)| p * (1.0 + sigma * b.x))
            .collect();
        let mesh = Mesh::from_triangles(&noisy, &tris).expect("sphere").mesh;
        (mesh, clean)
    }

    fn rms_radius_error(positions: &[DVec3]) -> f64 {
        let sum: f64 = positions.iter().map(|p| (p.length() - 1.0).powi(2)).sum();
        (sum / positions.len() as f64).sqrt()
    }

    #[test]
    fn the_noise_estimate_follows_the_noise_put_in() {
        for sigma in [0.005, 0.01, 0.02] {
            let (mesh, _) = noisy_sphere(sigma);
            let r = pyramid_denoise(&mesh, &PyramidDenoise::default(), &NoProgress).unwrap();
            assert!(
                (0.6 * sigma..1.6 * sigma).contains(&r.noise),
                "estimated {} for {sigma}",
                r.noise
            );
            assert_eq!(r.gains[0], 0.0, "the finest octave is noise");
            assert!(r.gains.last().is_some_and(|&g| g > 0.9), "{:?}", r.gains);
        }
    }

    #[test]
    fn it_removes_most_of_the_noise_and_strength_removes_more_or_less() {
        let (mesh, _) = noisy_sphere(0.01);
        let noisy = rms_radius_error(&mesh.positions());
        let run = |strength| {
            let options = PyramidDenoise { strength };
            let r = pyramid_denoise(&mesh, &options, &NoProgress).unwrap();
            (rms_radius_error(&r.positions), r.gains)
        };
        let (default, gains) = run(1.0);
        assert!(default < 0.5 * noisy, "{default} from {noisy}");
        let (_, weaker) = run(0.5);
        let (_, stronger) = run(2.0);
        for o in 0..gains.len() {
            assert!(weaker[o] >= gains[o] && gains[o] >= stronger[o]);
        }
        let (none, _) = run(0.0);
        assert_eq!(none, noisy);
    }

    #[test]
    fn bad_strength_is_refused() {
        for strength in [-1.0, f64::NAN, f64::INFINITY] {
            assert!(PyramidDenoise { strength }.validate().is_err());
        }
    }
}
