//! The order of the collapses of one round of a partitioned build: the blocks' sequences
//! merged by cost.
//!
//! The blocks of one round share no free vertex and no face, and a collapse reads and writes
//! only faces around its own free vertices, so collapses of different blocks commute: any
//! interleaving that keeps each block's own order is a valid collapse sequence with the same
//! result. Of those, the one that always takes the cheapest next collapse among the blocks'
//! heads is closest to the one-process build's global cost order, which keeps every level
//! of the hierarchy as even across the blocks as within one. Ties go to the lower block, so
//! the order depends on the results alone.

use super::super::decimate::Collapse;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The collapses of `blocks` (each in its own order) interleaved cheapest head first.
pub(crate) fn merge_by_cost(blocks: Vec<Vec<Collapse>>) -> Vec<Collapse> {
    let total = blocks.iter().map(Vec::len).sum();
    let mut out = Vec::with_capacity(total);
    let mut next = vec![0usize; blocks.len()];
    // Costs are squared distances (>= 0), whose bit patterns order like the numbers.
    let key = |c: &Collapse| c.error_sq.max(0.0).to_bits();
    let mut heads: BinaryHeap<Reverse<(u64, usize)>> = blocks
        .iter()
        .enumerate()
        .filter_map(|(b, s)| s.first().map(|c| Reverse((key(c), b))))
        .collect();
    while let Some(Reverse((_, b))) = heads.pop() {
        out.push(blocks[b][next[b]]);
        next[b] += 1;
        if let Some(c) = blocks[b].get(next[b]) {
            heads.push(Reverse((key(c), b)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(from: u32, error_sq: f64) -> Collapse {
        Collapse {
            from,
            to: 0,
            left: u32::MAX,
            right: u32::MAX,
            error_sq,
        }
    }

    #[test]
    fn blocks_interleave_by_cost_each_in_its_own_order() {
        let a = vec![c(1, 0.1), c(2, 0.5), c(3, 0.2)];
        let b = vec![c(4, 0.3), c(5, 0.3), c(6, 0.4)];
        let merged: Vec<u32> = merge_by_cost(vec![a, b]).iter().map(|x| x.from).collect();
        assert_eq!(merged, vec![1, 4, 5, 6, 2, 3]);
    }

    #[test]
    fn equal_costs_go_to_the_lower_block_first() {
        let merged = merge_by_cost(vec![vec![c(1, 0.2)], vec![c(2, 0.2)], vec![]]);
        assert_eq!(
            merged.iter().map(|x| x.from).collect::<Vec<_>>(),
            vec![1, 2]
        );
    }
}
