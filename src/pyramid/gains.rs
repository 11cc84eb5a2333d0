//! Filters as a gain per level (`docs/algorithms.md` §1c, "Filtering and editing").
//!
//! Synthesis adds the details of level `n` scaled by `g(n)`. A filter is a list of bands, each a
//! half-open level range `(from, to]` with a gain; where bands overlap their gains multiply.
//!
//! * low-pass `N`: `g = 0` on `(N, ∞)` — only the coarse shape up to level `N` survives;
//! * stop-band `A:B`: `g = 0` on `(A, B]`;
//! * enhancement `A:B=G`: `g = G` on `(A, B]`;
//! * generic gain `A:B=G`, repeatable.
//!
//! Levels are vertex counts (`1000`) or feature sizes in model units with a `u` suffix
//! (`0.02u`): a level with `n` vertices on a surface of area `A` has a typical edge length
//! `h = sqrt(2A / (√3 n))` (equilateral triangles, two per vertex), so a size `h` is the level
//! `n = 2A / (√3 h²)`. Larger features are coarser levels; a band given in sizes may list them
//! in either order.
//!
//! `normal_only` applies the gains to the normal component of the details only, which keeps
//! vertices from drifting tangentially when details are amplified or removed.

use std::fmt;
use std::str::FromStr;

/// A level given as a vertex count or as a feature size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LevelSpec {
    /// A vertex count.
    Vertices(usize),
    /// A feature size (typical edge length) in model units.
    FeatureSize(f64),
}

impl LevelSpec {
    /// The level for a surface of total area `area`.
    pub fn resolve(self, area: f64) -> usize {
        match self {
            LevelSpec::Vertices(n) => n,
            LevelSpec::FeatureSize(h) => level_for_feature_size(h, area),
        }
    }
}

/// A plain number is a vertex count: `Filter::new().lowpass(1000)`.
impl From<usize> for LevelSpec {
    fn from(n: usize) -> Self {
        LevelSpec::Vertices(n)
    }
}

/// The level whose typical edge length is `size` on a surface of area `area`
/// (`n = 2A / (√3 h²)`, rounded; `usize::MAX` for a zero size).
pub(crate) fn level_for_feature_size(size: f64, area: f64) -> usize {
    let n = 2.0 * area / (3f64.sqrt() * size * size);
    if n.is_finite() {
        n.round().max(0.0) as usize
    } else {
        usize::MAX
    }
}

/// The typical edge length at level `n` on a surface of area `area`.
pub(crate) fn feature_size_of_level(n: usize, area: f64) -> f64 {
    (2.0 * area / (3f64.sqrt() * n.max(1) as f64)).sqrt()
}

/// Why a band or level could not be parsed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{text:?}: {reason}")]
pub struct GainParseError {
    /// The text as given.
    pub text: String,
    /// What is wrong and what is expected.
    pub reason: String,
}

fn parse_error(text: &str, reason: impl Into<String>) -> GainParseError {
    GainParseError {
        text: text.into(),
        reason: reason.into(),
    }
}

impl LevelSpec {
    /// `self` as the level of a low-pass, which keeps the levels up to it: at least one vertex
    /// (a band may start at level 0, a low-pass may not). `text` is the level as the caller
    /// wrote it, for the message.
    pub fn for_lowpass(self, text: &str) -> Result<LevelSpec, GainParseError> {
        match self {
            LevelSpec::Vertices(0) => Err(parse_error(
                text,
                "a low-pass keeps the levels up to N vertices, so N must be at least 1",
            )),
            level => Ok(level),
        }
    }
}

impl FromStr for LevelSpec {
    type Err = GainParseError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim();
        if t.starts_with('-') {
            return Err(parse_error(
                s,
                "a level is a vertex count or a positive feature size, not a negative number",
            ));
        }
        if let Some(size) = t.strip_suffix('u') {
            let h: f64 = size.trim().parse().map_err(|_| {
                parse_error(s, "expected a feature size in model units such as 0.02u")
            })?;
            if !(h > 0.0 && h.is_finite()) {
                return Err(parse_error(s, "a feature size must be positive and finite"));
            }
            return Ok(LevelSpec::FeatureSize(h));
        }
        t.parse::<usize>().map(LevelSpec::Vertices).map_err(|_| {
            parse_error(
                s,
                "expected a level as a vertex count (1000) or a feature size with a `u` suffix (0.02u)",
            )
        })
    }
}

impl fmt::Display for LevelSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LevelSpec::Vertices(n) => write!(f, "{n}"),
            LevelSpec::FeatureSize(h) => write!(f, "{h}u"),
        }
    }
}

/// One band `(from, to]` with a gain. `to = None` means "up to the finest level".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GainBand {
    /// Lower end (exclusive).
    pub from: LevelSpec,
    /// Upper end (inclusive); `None` for no upper end.
    pub to: Option<LevelSpec>,
    /// Factor applied to the details of the levels in the band.
    pub gain: f64,
}

impl GainBand {
    /// Parses `A:B` (a band, gain left to the caller) into its two ends.
    pub fn parse_band(s: &str) -> Result<(LevelSpec, LevelSpec), GainParseError> {
        let (a, b) = s
            .split_once(':')
            .ok_or_else(|| parse_error(s, "expected a band A:B such as 1000:15000"))?;
        let (from, to) = (a.parse()?, b.parse()?);
        // Vertex counts must come coarse to fine; feature sizes may come in either order
        // (see the module docs), and a mixed band is ordered only once it meets a surface.
        if let (LevelSpec::Vertices(x), LevelSpec::Vertices(y)) = (from, to)
            && x > y
        {
            return Err(parse_error(
                s,
                format!("a band A:B runs from the coarser level to the finer one: write {y}:{x}"),
            ));
        }
        Ok((from, to))
    }

    /// Parses `A:B=G`.
    pub fn parse_with_gain(s: &str) -> Result<GainBand, GainParseError> {
        let (band, gain) = s
            .split_once('=')
            .ok_or_else(|| parse_error(s, "expected A:B=G such as 1000:15000=2"))?;
        let (from, to) = Self::parse_band(band)?;
        let gain: f64 = gain
            .trim()
            .parse()
            .map_err(|_| parse_error(s, "the gain after `=` must be a number"))?;
        if !gain.is_finite() {
            return Err(parse_error(s, "the gain must be finite"));
        }
        Ok(GainBand {
            from,
            to: Some(to),
            gain,
        })
    }
}

/// A filter: gain bands plus the normal-only switch. Resolve it against a surface with
/// [`Filter::resolve`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Filter {
    /// The bands; gains multiply where they overlap.
    pub bands: Vec<GainBand>,
    /// Scale only the normal component of the details (default false).
    pub normal_only: bool,
}

impl Filter {
    /// The identity filter (every gain 1), to build on with the methods below.
    pub fn new() -> Self {
        Filter::default()
    }

    /// Zero every level above `n` (a vertex count, or a [`LevelSpec`]).
    pub fn lowpass(mut self, n: impl Into<LevelSpec>) -> Self {
        self.bands.push(GainBand {
            from: n.into(),
            to: None,
            gain: 0.0,
        });
        self
    }

    /// Zero the levels in `(a, b]`.
    pub fn stopband(self, a: impl Into<LevelSpec>, b: impl Into<LevelSpec>) -> Self {
        self.gain(a, b, 0.0)
    }

    /// Multiply the levels in `(a, b]` by `g` (`g > 1` enhances).
    pub fn gain(mut self, a: impl Into<LevelSpec>, b: impl Into<LevelSpec>, g: f64) -> Self {
        self.bands.push(GainBand {
            from: a.into(),
            to: Some(b.into()),
            gain: g,
        });
        self
    }

    /// Scale only the normal component of the details.
    pub fn normal_only(mut self) -> Self {
        self.normal_only = true;
        self
    }

    /// The paper's three Venus experiments (Guskov, Sweldens, Schröder 1999, Fig. 9), as
    /// `(name, description, filter)`: low-pass above level 1000, stop-band 1000–15000 and
    /// enhancement ×2 on 1000–15000. The demo writes them; the benches time them.
    ///
    /// ```
    /// use meshpyr::pyramid::Filter;
    /// let names: Vec<&str> = Filter::paper_experiments().iter().map(|e| e.0).collect();
    /// assert_eq!(names, ["lowpass", "stopband", "enhanced"]);
    /// ```
    pub fn paper_experiments() -> [(&'static str, &'static str, Filter); 3] {
        let (a, b) = (LevelSpec::Vertices(1000), LevelSpec::Vertices(15000));
        [
            (
                "lowpass",
                "low-pass above level 1000",
                Filter::default().lowpass(a),
            ),
            (
                "stopband",
                "stop-band 1000-15000",
                Filter::default().stopband(a, b),
            ),
            (
                "enhanced",
                "enhancement x2 on 1000-15000",
                Filter::default().gain(a, b, 2.0),
            ),
        ]
    }

    /// True when no band is set (synthesis reproduces the input).
    #[cfg(test)]
    pub(crate) fn is_identity(&self) -> bool {
        self.bands.iter().all(|b| b.gain == 1.0)
    }

    /// Levels of every band for a surface of area `area`.
    pub fn resolve(&self, area: f64) -> LevelGains {
        let bands = self
            .bands
            .iter()
            .map(|b| {
                let a = b.from.resolve(area);
                let c = b.to.map_or(usize::MAX, |t| t.resolve(area));
                // Sizes run the other way round from levels: accept either order.
                (a.min(c), a.max(c), b.gain)
            })
            .collect();
        LevelGains {
            bands,
            normal_only: self.normal_only,
        }
    }
}

/// A filter resolved to levels: `g(n)` is the product of the gains of the bands `(lo, hi]` that
/// contain `n`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LevelGains {
    /// `(lo, hi, gain)` per band, levels half-open `(lo, hi]`.
    pub bands: Vec<(usize, usize, f64)>,
    /// Scale only the normal component of the details.
    pub normal_only: bool,
}

impl LevelGains {
    /// Gain 1 everywhere: synthesis reproduces the analysed signal.
    pub fn unit() -> LevelGains {
        LevelGains::default()
    }

    /// True when every level's gain is 1 (synthesis then gives the analysed signal back).
    pub fn is_unit(&self) -> bool {
        self.bands.iter().all(|b| b.2 == 1.0)
    }

    /// The gain of level `n`.
    #[inline]
    pub fn gain(&self, n: usize) -> f64 {
        self.bands
            .iter()
            .filter(|&&(lo, hi, _)| lo < n && n <= hi)
            .map(|b| b.2)
            .product()
    }

    /// `(tangential, normal)` gains of level `n`.
    #[inline]
    pub(crate) fn split_gain(&self, n: usize) -> (f64, f64) {
        let g = self.gain(n);
        if self.normal_only { (1.0, g) } else { (g, g) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_filters_resolve_to_the_right_levels() {
        let f = Filter::default().lowpass(LevelSpec::Vertices(1000)).gain(
            LevelSpec::Vertices(1000),
            LevelSpec::Vertices(15000),
            2.0,
        );
        let g = f.resolve(1.0);
        assert_eq!(g.gain(1000), 1.0);
        assert_eq!(g.gain(1001), 0.0);
        assert_eq!(g.gain(999), 1.0);
        let s = Filter::default()
            .stopband(LevelSpec::Vertices(1000), LevelSpec::Vertices(15000))
            .resolve(1.0);
        assert_eq!(
            [500, 1000, 1001, 15000, 15001].map(|n| s.gain(n)),
            [1.0, 1.0, 0.0, 0.0, 1.0]
        );
        let e = Filter::default()
            .gain(LevelSpec::Vertices(1000), LevelSpec::Vertices(15000), 2.0)
            .gain(LevelSpec::Vertices(10000), LevelSpec::Vertices(20000), 3.0)
            .resolve(1.0);
        assert_eq!(
            [1000, 5000, 12000, 18000].map(|n| e.gain(n)),
            [1.0, 2.0, 6.0, 3.0]
        );
    }

    #[test]
    fn feature_sizes_convert_both_ways_and_bands_accept_either_order() {
        let area = 3.0;
        for n in [10usize, 1000, 123_456] {
            let h = feature_size_of_level(n, area);
            assert_eq!(level_for_feature_size(h, area), n);
        }
        // Equilateral unit triangles, two per vertex: n vertices cover n·√3/2.
        let n = 400;
        assert!((feature_size_of_level(n, n as f64 * 3f64.sqrt() / 2.0) - 1.0).abs() < 1e-12);
        let big = LevelSpec::FeatureSize(0.1);
        let small = LevelSpec::FeatureSize(0.01);
        let a = Filter::default().stopband(big, small).resolve(area);
        let b = Filter::default().stopband(small, big).resolve(area);
        assert_eq!(a, b);
        assert!(a.bands[0].0 < a.bands[0].1);
    }

    #[test]
    fn parsing_accepts_counts_sizes_and_rejects_garbage() {
        assert_eq!("1000".parse::<LevelSpec>(), Ok(LevelSpec::Vertices(1000)));
        assert_eq!("0.5u".parse::<LevelSpec>(), Ok(LevelSpec::FeatureSize(0.5)));
        assert_eq!(
            GainBand::parse_with_gain("1000:15000=2").unwrap(),
            GainBand {
                from: LevelSpec::Vertices(1000),
                to: Some(LevelSpec::Vertices(15000)),
                gain: 2.0
            }
        );
        for bad in ["", "-3", "1e3", "0u", "-1u", "nanu", "abc"] {
            assert!(bad.parse::<LevelSpec>().is_err(), "{bad}");
        }
        for bad in ["1000", "1000:15000", "1000:x=2", "1:2=", "1:2=inf", "1-2=3"] {
            assert!(GainBand::parse_with_gain(bad).is_err(), "{bad}");
        }
        let e = GainBand::parse_with_gain("1:2=q").unwrap_err();
        assert!(e.to_string().contains("gain"), "{e}");
    }

    #[test]
    fn normal_only_keeps_tangential_gain_one() {
        let mut f = Filter::default().stopband(LevelSpec::Vertices(0), LevelSpec::Vertices(10));
        assert_eq!(f.resolve(1.0).split_gain(5), (0.0, 0.0));
        f.normal_only = true;
        assert_eq!(f.resolve(1.0).split_gain(5), (1.0, 0.0));
        assert_eq!(f.resolve(1.0).split_gain(50), (1.0, 1.0));
        assert!(!f.is_identity());
        assert!(Filter::default().is_identity());
    }
}
