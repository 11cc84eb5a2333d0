//! The vertices a partitioned build pinned, pass by pass (`docs/partitioned.md`, "The detail
//! pyramid on a partitioned hierarchy").
//!
//! A pass of the partitioned build collapses only edges whose ends are both free; the vertices
//! of faces across its cells are pinned for the pass. The detail pyramid of such a hierarchy
//! leaves the ring vertices that are pinned in a split's pass untouched, so that the analysis
//! of every block reads, outside its own free vertices, only values no block writes during the
//! pass. That rule needs, per split, the pinned set of its pass.
//!
//! A pass's collapses are one contiguous run of the collapse sequence, and the progressive
//! mesh stores the sequence reversed, so a pass is one contiguous run of splits: the record is
//! per pass (coarsest first) the end of its run and its pinned vertices, sorted, in PM
//! indices. A pass's vertices are pinned at most once and a border is a small share of a
//! block, so this stays a fraction of the vertex count.

use std::ops::Range;

/// Per pass of a partitioned build, its run of splits and the vertices pinned in it (PM
/// indices, ascending). Passes are in split order: the last block's (nothing pinned) first,
/// the first pass's last.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Pins {
    /// Per pass, the end (exclusive) of its run of splits; ascending, the last one the number
    /// of splits. A pass's run starts where the one before ends (the first at 0).
    ends: Vec<u32>,
    /// Per pass, its pinned vertices, ascending.
    pinned: Vec<Vec<u32>>,
}

/// Why a pin record does not fit a hierarchy.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("pinned vertices: {0}")]
pub struct PinsError(pub String);

impl Pins {
    /// Passes given in split order as `(number of splits, pinned vertices)`; passes without
    /// splits are dropped, the vertices sorted. Checks nothing against a hierarchy (see
    /// [`Self::check`]).
    pub fn from_passes(passes: impl IntoIterator<Item = (usize, Vec<u32>)>) -> Pins {
        let mut pins = Pins::default();
        let mut end = 0u32;
        for (n, mut pinned) in passes {
            if n == 0 {
                continue;
            }
            end += n as u32;
            pinned.sort_unstable();
            pinned.dedup();
            pins.ends.push(end);
            pins.pinned.push(pinned);
        }
        pins
    }

    /// The passes in split order: each one's run of splits and its pinned vertices.
    pub fn passes(&self) -> impl Iterator<Item = (Range<usize>, &[u32])> + '_ {
        let starts = std::iter::once(0).chain(self.ends.iter().copied());
        starts
            .zip(&self.ends)
            .zip(&self.pinned)
            .map(|((a, &b), p)| (a as usize..b as usize, p.as_slice()))
    }

    /// The number of passes (with at least one split).
    pub fn n_passes(&self) -> usize {
        self.ends.len()
    }

    /// The number of splits the record covers.
    pub fn n_splits(&self) -> usize {
        self.ends.last().map_or(0, |&e| e as usize)
    }

    /// The vertices pinned in the pass of split `k` (empty beyond the record).
    pub fn pinned_at(&self, k: usize) -> &[u32] {
        let pass = self.ends.partition_point(|&e| e as usize <= k);
        self.pinned.get(pass).map_or(&[], Vec::as_slice)
    }

    /// Whether any vertex is pinned in any pass: a record without is the one-process rule.
    pub fn is_empty(&self) -> bool {
        self.pinned.iter().all(Vec::is_empty)
    }

    /// Checks the record against a hierarchy of `n_base` base vertices and `n_splits`
    /// splits, split `k` removing vertex `n_base + k` into `survivor(k)`: the passes cover the
    /// splits exactly, each pass's vertices are ascending and exist during the pass (below
    /// the level its last split makes), and no split's vertex or survivor is pinned in its
    /// pass (a pass collapses only free edges).
    pub fn check(
        &self,
        n_base: usize,
        n_splits: usize,
        survivor: impl Fn(usize) -> u32,
    ) -> Result<(), PinsError> {
        if self.n_splits() != n_splits {
            return Err(PinsError(format!(
                "the passes cover {} splits, the hierarchy has {n_splits}",
                self.n_splits()
            )));
        }
        for (p, (run, pinned)) in self.passes().enumerate() {
            if pinned.windows(2).any(|w| w[0] >= w[1]) {
                return Err(PinsError(format!("pass {p}: vertices not ascending")));
            }
            let level = n_base + run.end;
            if let Some(&v) = pinned.last().filter(|&&v| v as usize >= level) {
                return Err(PinsError(format!(
                    "pass {p}: vertex {v} does not exist during the pass (level {level})"
                )));
            }
            for k in run {
                let (v, t) = ((n_base + k) as u32, survivor(k));
                if let Some(x) = [v, t].into_iter().find(|x| pinned.binary_search(x).is_ok()) {
                    return Err(PinsError(format!(
                        "split {k} collapses vertex {v} into {t}, and {x} is pinned in its pass"
                    )));
                }
            }
        }
        Ok(())
    }

    /// The parts of the record: per pass the end of its run of splits, and its pinned
    /// vertices (what a file stores).
    pub fn parts(&self) -> (&[u32], &[Vec<u32>]) {
        (&self.ends, &self.pinned)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_split_sees_the_pins_of_its_own_pass() {
        let pins = Pins::from_passes([(2, vec![]), (0, vec![9]), (3, vec![7, 4, 4])]);
        assert_eq!(pins.n_passes(), 2);
        assert_eq!(pins.n_splits(), 5);
        assert_eq!(pins.pinned_at(0), &[] as &[u32]);
        assert_eq!(pins.pinned_at(1), &[] as &[u32]);
        assert_eq!(pins.pinned_at(2), &[4, 7]);
        assert_eq!(pins.pinned_at(4), &[4, 7]);
        assert_eq!(pins.pinned_at(5), &[] as &[u32]);
        let runs: Vec<_> = pins.passes().map(|(r, _)| r).collect();
        assert_eq!(runs, vec![0..2, 2..5]);
    }

    #[test]
    fn a_record_pinning_a_collapsed_vertex_or_missing_splits_is_refused() {
        let pins = Pins::from_passes([(1, vec![]), (2, vec![3])]);
        // Splits 0, 1, 2 make vertices 4, 5, 6 (base of 4), each into one survivor.
        let check = |n, pins: &Pins, survivor: u32| pins.check(4, n, |_| survivor);
        assert!(check(3, &pins, 0).is_ok());
        assert!(check(4, &pins, 0).is_err());
        assert!(check(3, &pins, 3).is_err());
        let pins = Pins::from_passes([(1, vec![]), (2, vec![5])]);
        assert!(check(3, &pins, 0).is_err());
        // Vertex 6 is made by the pass's last split: it does not exist during it.
        let pins = Pins::from_passes([(3, vec![6])]);
        assert!(check(3, &pins, 0).is_err());
    }
}
