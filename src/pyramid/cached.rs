//! Re-filtering that resumes where the gains first change: an interactive equalizer moves one
//! band at a time, and the levels below that band synthesise exactly as before, so their
//! signal is kept at a few checkpoint levels and synthesis restarts from the last checkpoint
//! below the first level whose gain changed.
//!
//! Resuming is bit-identical to synthesising from the base: a checkpoint holds `f^(c)` on
//! vertices `0..c` exactly as the ranged synthesis [`DetailPyramid::synthesize_range`] leaves
//! it, and running the splits of `(n0, c]` then those of `(c, n]` is what a full synthesis does
//! up to the order of independent splits, which read nothing the others write.

use super::DetailPyramid;
use super::gains::LevelGains;
use glam::DVec3;

/// The signal `f^(level)` on vertices `0..level`, as synthesis with the current gains left it.
#[derive(Clone, Debug)]
struct Checkpoint {
    level: usize,
    prefix: Vec<DVec3>,
}

/// A synthesis that remembers its last gains and intermediate levels, so that the next call
/// re-runs only the levels from the first one whose gain changed (see the module docs). The
/// result is bit-identical to [`DetailPyramid::synthesize`] with the same gains.
///
/// A cache belongs to the pyramid it was made for; pass that pyramid to every call.
///
/// ```
/// use meshpyr::pyramid::{Filter, SynthesisCache};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let scan = meshpyr::read_mesh("tests/data/mc/mc_bunny_vox40.ply")?;
/// let p = meshpyr::Pyramid::build(&scan)?.pyramid;
/// let mut cache = SynthesisCache::octaves(&p);
/// cache.synthesize(&p, &Filter::new().resolve(p.surface_area()));
/// let top = *p.levels_of_octaves().last().unwrap();
/// let enhanced = Filter::new().gain(top.0, top.1, 2.0).resolve(p.surface_area());
/// let fast = cache.synthesize(&p, &enhanced).to_vec();
/// assert_eq!(cache.resumed_from(), top.0);
/// assert_eq!(fast, p.synthesize(&enhanced));
/// # Ok(()) }
/// ```
#[derive(Clone, Debug, Default)]
pub struct SynthesisCache {
    checkpoints: Vec<Checkpoint>,
    /// The gains `signal` was synthesised with; `None` before the first call.
    gains: Option<LevelGains>,
    signal: Vec<DVec3>,
    resumed_from: usize,
    /// The level synthesis stops at ([`SynthesisCache::up_to`]); `None`: the finest.
    top: Option<usize>,
}

impl SynthesisCache {
    /// A cache keeping checkpoints at `levels` (those strictly between the base level and the
    /// finest are used; order and repeats do not matter).
    pub fn new(pyramid: &DetailPyramid, levels: &[usize]) -> Self {
        let mut levels: Vec<usize> = levels
            .iter()
            .copied()
            .filter(|&c| c > pyramid.n_base && c < pyramid.n_finest)
            .collect();
        levels.sort_unstable();
        levels.dedup();
        SynthesisCache {
            checkpoints: levels
                .into_iter()
                .map(|level| Checkpoint {
                    level,
                    prefix: Vec::new(),
                })
                .collect(),
            ..Default::default()
        }
    }

    /// A cache with a checkpoint at the start of every octave band
    /// ([`DetailPyramid::levels_of_octaves`]), where an equalizer's gains change.
    pub fn octaves(pyramid: &DetailPyramid) -> Self {
        let starts: Vec<usize> = pyramid.levels_of_octaves().iter().map(|b| b.0).collect();
        SynthesisCache::new(pyramid, &starts)
    }

    /// A cache that synthesises only up to level `top` (clamped to the pyramid's levels), with
    /// checkpoints at the octave starts below it: [`SynthesisCache::synthesize`] then returns
    /// `f^(top)` on PM vertices `0..top`, bit-identical to the first `top` values of
    /// [`DetailPyramid::signal_at_level`] with the same gains, and costs at most the splits up to
    /// `top` (an editor's preview of a coarse level of a large scan). Gains of finer levels
    /// cannot change it, so changing only those recomputes nothing.
    pub fn up_to(pyramid: &DetailPyramid, top: usize) -> Self {
        let top = top.clamp(pyramid.n_base, pyramid.n_finest);
        let starts: Vec<usize> = pyramid
            .levels_of_octaves()
            .iter()
            .map(|b| b.0)
            .filter(|&c| c < top)
            .collect();
        SynthesisCache {
            top: Some(top),
            ..SynthesisCache::new(pyramid, &starts)
        }
    }

    /// The level synthesis runs to and the length of the signal it returns.
    fn top_and_len(&self, pyramid: &DetailPyramid) -> (usize, usize) {
        match self.top {
            Some(top) => (top, top),
            None => (pyramid.n_finest, pyramid.signal_len()),
        }
    }

    /// The level the last [`SynthesisCache::synthesize`] resumed from: the base level after a
    /// full synthesis, the finest when nothing changed.
    pub fn resumed_from(&self) -> usize {
        self.resumed_from
    }

    /// The finest signal with `gains` (PM order, as [`DetailPyramid::synthesize`] returns it),
    /// re-running only the levels from the last checkpoint below the first changed gain.
    pub fn synthesize(&mut self, pyramid: &DetailPyramid, gains: &LevelGains) -> &[DVec3] {
        let (top, len) = self.top_and_len(pyramid);
        let fits = self.signal.len() == len;
        let changed = match (&self.gains, fits) {
            (Some(old), true) => first_changed_level(pyramid, old, gains),
            _ => Some(pyramid.n_base + 1),
        };
        let Some(changed) = changed.filter(|&c| c <= top) else {
            self.resumed_from = top;
            return &self.signal;
        };
        let start = self.restore_below(pyramid, changed);
        self.resume(pyramid, start, gains);
        self.gains = Some(gains.clone());
        &self.signal
    }

    /// Sets the signal to the last checkpoint at or below `changed − 1` (the base signal when
    /// there is none) and returns that checkpoint's level.
    fn restore_below(&mut self, pyramid: &DetailPyramid, changed: usize) -> usize {
        let (top, len) = self.top_and_len(pyramid);
        if self.signal.len() != len {
            self.signal = if self.top.is_some() {
                let mut f = vec![DVec3::ZERO; len];
                f[..pyramid.n_base].copy_from_slice(pyramid.base());
                f
            } else {
                pyramid.base_signal()
            };
            for c in &mut self.checkpoints {
                c.prefix.clear();
            }
            return pyramid.n_base;
        }
        let usable = self
            .checkpoints
            .iter()
            .rev()
            .find(|c| c.level < changed && c.prefix.len() == c.level);
        let start = match usable {
            Some(c) => {
                self.signal[..c.level].copy_from_slice(&c.prefix);
                c.level
            }
            None => {
                self.signal[..pyramid.n_base].copy_from_slice(&pyramid.base);
                pyramid.n_base
            }
        };
        // The vertices synthesis will create hold the base signal's zeros again, as in a
        // synthesis from the base; those without faces (after `n_finest`) never change.
        self.signal[start..top].fill(DVec3::ZERO);
        start
    }

    /// Synthesises from level `start` to the finest, refreshing the checkpoints above `start`.
    fn resume(&mut self, pyramid: &DetailPyramid, start: usize, gains: &LevelGains) {
        self.resumed_from = start;
        let mut level = start;
        for c in self.checkpoints.iter_mut().filter(|c| c.level > start) {
            pyramid.synthesize_range(&mut self.signal, level, c.level, gains);
            c.prefix.clear();
            c.prefix.extend_from_slice(&self.signal[..c.level]);
            level = c.level;
        }
        let (top, _) = self.top_and_len(pyramid);
        pyramid.synthesize_range(&mut self.signal, level, top, gains);
    }
}

/// The first level in `(n0, n]` whose `(tangential, normal)` gain differs between `old` and
/// `new`, or `None`. Gains are constant between band ends, so one level per stretch decides.
fn first_changed_level(
    pyramid: &DetailPyramid,
    old: &LevelGains,
    new: &LevelGains,
) -> Option<usize> {
    let (n0, n) = (pyramid.n_base, pyramid.n_finest);
    let mut ends: Vec<usize> = std::iter::once(n0)
        .chain(old.bands.iter().chain(&new.bands).flat_map(|b| [b.0, b.1]))
        .filter(|&e| e >= n0 && e < n)
        .collect();
    ends.sort_unstable();
    ends.dedup();
    ends.into_iter()
        .map(|e| e + 1)
        .find(|&level| old.split_gain(level) != new.split_gain(level))
}

impl DetailPyramid {
    /// The octave bands of levels `(lo, hi]` (those of [`DetailPyramid::spectrum`]), coarse to
    /// fine: where an equalizer puts its sliders.
    /// They depend on the level counts only, so no detail is read.
    pub fn levels_of_octaves(&self) -> Vec<(usize, usize)> {
        super::spectrum::octave_bands(self.n_base, self.n_finest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::pm::{PmOptions, ProgressiveMesh};
    use crate::progress::NoProgress;
    use crate::pyramid::Filter;
    use crate::relax::SecondDifference;

    fn bumpy_torus_pyramid() -> DetailPyramid {
        let (p, t) = crate::mesh::shapes::torus(40, 24, |u, v| {
            let r = 2.0 + (1.0 + 0.15 * (7.0 * u).sin() * (5.0 * v).cos()) * v.cos();
            DVec3::new(r * u.cos(), r * u.sin(), v.sin())
        });
        let mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
        let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
        DetailPyramid::analyze(&pm, &SecondDifference::default(), &NoProgress).unwrap()
    }

    fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
        v.iter().map(|x| x.to_array().map(f64::to_bits)).collect()
    }

    /// Gains as an equalizer sets them: one per octave band.
    fn equalizer(p: &DetailPyramid, gains: &[f64], normal_only: bool) -> LevelGains {
        let mut f = Filter::new();
        for (&(lo, hi), &g) in p.levels_of_octaves().iter().zip(gains) {
            f = f.gain(lo, hi, g);
        }
        f.normal_only = normal_only;
        f.resolve(p.surface_area())
    }

    #[test]
    fn every_slider_sequence_gives_the_bits_of_a_fresh_synthesis() {
        let p = bumpy_torus_pyramid();
        let bands = p.levels_of_octaves();
        assert!(bands.len() >= 4, "{bands:?}");
        let mut cache = SynthesisCache::octaves(&p);
        let mut gains = vec![1.0; bands.len()];
        let moves = [
            (bands.len() - 1, 2.5),
            (1, 0.0),
            (2, 1.7),
            (1, 1.0),
            (0, 0.3),
        ];
        for (normal_only, (band, g)) in [false, false, true, true, false].into_iter().zip(moves) {
            gains[band] = g;
            let level_gains = equalizer(&p, &gains, normal_only);
            let cached = cache.synthesize(&p, &level_gains).to_vec();
            assert_eq!(bits(&cached), bits(&p.synthesize(&level_gains)));
        }
    }

    #[test]
    fn a_fine_band_resumes_from_its_octave_and_no_change_recomputes_nothing() {
        let p = bumpy_torus_pyramid();
        let bands = p.levels_of_octaves();
        let mut cache = SynthesisCache::octaves(&p);
        let mut gains = vec![1.0; bands.len()];
        cache.synthesize(&p, &equalizer(&p, &gains, false));
        assert_eq!(cache.resumed_from(), p.n_base_vertices());
        let last = bands.len() - 1;
        gains[last] = 2.0;
        cache.synthesize(&p, &equalizer(&p, &gains, false));
        assert_eq!(cache.resumed_from(), bands[last].0);
        cache.synthesize(&p, &equalizer(&p, &gains, false));
        assert_eq!(cache.resumed_from(), p.n_vertices());
        // Normal-only changes every level whose gain is not one: here the finest band only.
        cache.synthesize(&p, &equalizer(&p, &gains, true));
        assert_eq!(cache.resumed_from(), bands[last].0);
    }

    #[test]
    fn a_cache_up_to_a_level_gives_the_bits_of_that_level_and_ignores_finer_gains() {
        let p = bumpy_torus_pyramid();
        let bands = p.levels_of_octaves();
        let top = bands[bands.len() - 2].0 + 7;
        let mut cache = SynthesisCache::up_to(&p, top);
        let mut gains = vec![1.0; bands.len()];
        for (band, g) in [(1, 2.5), (bands.len() - 3, 0.0), (bands.len() - 1, 3.0)] {
            gains[band] = g;
            let level_gains = equalizer(&p, &gains, false);
            let mut full = p.base_signal();
            p.synthesize_range(&mut full, p.n_base_vertices(), top, &level_gains);
            let cached = cache.synthesize(&p, &level_gains).to_vec();
            assert_eq!(bits(&cached), bits(&full[..top]));
        }
        // The last move was above `top`: nothing was recomputed.
        assert_eq!(cache.resumed_from(), top);
    }

    #[test]
    fn changes_between_checkpoints_resume_from_the_checkpoint_below() {
        let p = bumpy_torus_pyramid();
        let (n0, n) = (p.n_base_vertices(), p.n_vertices());
        let c = n0 + (n - n0) / 3;
        let mut cache = SynthesisCache::new(&p, &[c, 0, n + 5]);
        cache.synthesize(&p, &LevelGains::unit());
        let g = Filter::new().gain(c + 10, n, 1.5).resolve(1.0);
        let cached = cache.synthesize(&p, &g).to_vec();
        assert_eq!(cache.resumed_from(), c);
        assert_eq!(bits(&cached), bits(&p.synthesize(&g)));
        let below = Filter::new().gain(c - 1, n, 1.5).resolve(1.0);
        let cached = cache.synthesize(&p, &below).to_vec();
        assert_eq!(cache.resumed_from(), n0);
        assert_eq!(bits(&cached), bits(&p.synthesize(&below)));
    }
}
