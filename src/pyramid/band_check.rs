//! Warnings for filter bands that would change nothing, or less than they say, on a pyramid.

use super::{DetailPyramid, Filter};

impl DetailPyramid {
    /// One sentence for every band of `filter` that selects none of this pyramid's levels (an
    /// empty band, a stop-band above the finest level, a feature size finer than the scan's
    /// sampling), which would otherwise change nothing without a word, and for every band that
    /// reaches below the coarsest level (a low-pass to fewer vertices than the base has), which
    /// would otherwise silently do less. Bands with gain 1 are never reported.
    pub fn band_warnings(&self, filter: &Filter) -> Vec<String> {
        self.band_warnings_below(filter, "no legal collapse goes further")
    }

    /// [`Self::band_warnings`], saying why no level lies below the base with `floor`.
    pub(crate) fn band_warnings_below(&self, filter: &Filter, floor: &str) -> Vec<String> {
        let gains = filter.resolve(self.surface_area());
        // Splits create the levels (base, finest]; a band (a, b] reaches them when it is not
        // empty and overlaps them.
        let (base, finest) = (self.n_base_vertices(), self.n_vertices());
        let mut warnings = Vec::new();
        for (band, &(a, b, gain)) in filter.bands.iter().zip(&gains.bands) {
            if gain == 1.0 {
                continue;
            }
            let (what, selects) = match band.to {
                Some(to) => (
                    format!("band {}:{to}", band.from),
                    format!("levels {}..={b}", a + 1),
                ),
                None => (
                    format!("low-pass {}", band.from),
                    format!("levels above {a}"),
                ),
            };
            if a >= b {
                warnings.push(format!("{what} is empty; it changes nothing"));
            } else if a >= finest || b <= base {
                warnings.push(format!(
                    "{what} selects {selects}, but the pyramid's levels are {}..={finest}; it \
                     changes nothing",
                    base + 1
                ));
            } else if a < base {
                let same = match band.to {
                    Some(to) => format!("band {base}:{to}"),
                    None => format!("low-pass {base}"),
                };
                warnings.push(format!(
                    "{what} reaches below the pyramid's coarsest level, {base} vertices \
                     ({floor}); levels {}..={base} do not exist, so it acts on levels {}..={} \
                     only ({same} does the same without this warning; `smooth` smooths further)",
                    a + 1,
                    base + 1,
                    b.min(finest)
                ));
            }
        }
        warnings
    }
}
