//! The `DETL` section (format 2.1, optional): every split's Burt–Adelson details in its local
//! frame, quantised to a power-of-two step below the bounding-box diagonal and Rice-coded
//! (`rice`), with the base signal and what the details were computed from (the analysis
//! version, the relaxation with its options, and the checksums of the `BASE` and `SPLT`
//! sections they were analysed on), so a reader can tell whether they fit the file and the
//! operator it is asked for.

use super::rice::{BitReader, BitWriter, Context};
use super::{FormatError, corrupt};
use crate::format::varint::{ByteReader, put_uvarint};
use crate::relax::RelaxationSpec;
use glam::DVec3;

/// The version of the analysis the stored details come from: bumped whenever the analysis
/// changes its output, so that details of an older analysis are recomputed, not used.
pub(crate) const ANALYSIS_VERSION: u8 = 3;

/// Splits per independently coded block (blocks decode on all cores).
const SPLITS_PER_BLOCK: usize = 4096;

/// The largest step exponent: `q · 2^969` stays finite for every `|q| < 2^53`.
const MAX_STEP_EXP: i32 = 969;

/// Quantised components are below this in magnitude, so `q · step` is exact.
const MAX_QUANTISED: i64 = 1 << 53;

/// Largest relaxation record a reader decodes (bincode, like `META`).
const MAX_RELAXATION: usize = 64;

/// Coding contexts: the split's detail count, then (new vertex, ring vertex) × (t1, t2, n).
const N_CONTEXTS: usize = 7;

/// The details of a pyramid in split order, as a `.pyr` file stores them (`formats/pyr.md`,
/// section `DETL`), with what they were computed with.
///
/// Each detail is held quantised: three integers `q` with detail `q · step` in its local frame
/// `(t1, t2, n)`, as the pyramid keeps them. Details read from a file stay coded (about a
/// fifth of their decoded size) until they are asked for ([`Self::for_each_block`],
/// [`Self::quantised`]), so that a reader never holds them twice: the pyramid decodes them
/// straight into its own order.
#[derive(Clone, Debug)]
pub struct StoredDetails {
    /// The relaxation operator, with its options, the details were analysed with.
    pub relaxation: RelaxationSpec,
    /// The base signal `f^(n0)` (exact).
    pub base: Vec<DVec3>,
    /// Per split, how many details it carries (the new vertex and its ring).
    pub counts: Vec<u32>,
    /// The quantisation step of every detail component (model units, a power of two): each
    /// component is a whole multiple of it.
    pub step: f64,
    values: Values,
}

/// Where a [`StoredDetails`]' values are.
#[derive(Clone, Debug)]
enum Values {
    /// Quantised, in split order.
    Quantised(Vec<[i32; 3]>),
    /// The section's coded blocks, checked when the file was read.
    Coded(CodedBlocks),
}

/// The coded blocks of a `DETL` section, copied out of the file.
#[derive(Clone, Debug)]
struct CodedBlocks {
    /// The blocks' bytes, one after another.
    bytes: Vec<u8>,
    /// Per block: its number of splits, its byte range in `bytes` and its offset in the file.
    blocks: Vec<(usize, std::ops::Range<usize>, u64)>,
    n_details: usize,
    /// The details' squares per octave, taken while the blocks were first decoded.
    squares: OctaveSquares,
}

/// `Σ q·q` over the components of the details of each octave of levels `(2^b, 2^(b+1)]`,
/// keyed by `2^(b+1)` (split `k` makes level `n_base + k + 1`), in key order, saturating. With
/// a power-of-two step these are the spectrum's energies in whole `step²`, so a reader that
/// took them while checking the blocks gives the spectrum without decoding the details again.
pub(crate) type OctaveSquares = Vec<(usize, u128)>;

/// Adds `sum` to the octave of `level` (levels come in increasing order).
fn add_square(squares: &mut OctaveSquares, level: usize, sum: u128) {
    let key = level.checked_next_power_of_two().unwrap_or(usize::MAX);
    match squares.last_mut() {
        Some((k, s)) if *k == key => *s = s.saturating_add(sum),
        _ => squares.push((key, sum)),
    }
}

/// `Σ q·q` of one detail (below 2^108: every component is below 2^53).
#[inline]
fn square(q: [i64; 3]) -> u128 {
    q.iter()
        .map(|&x| x.unsigned_abs() as u128 * x.unsigned_abs() as u128)
        .sum()
}

/// The octave squares of splits whose first makes level `first_level + 1`, with `counts` and
/// `details` in split order.
fn squares_of(first_level: usize, counts: &[u32], details: &[[i32; 3]]) -> OctaveSquares {
    let mut squares = OctaveSquares::new();
    let mut at = 0;
    for (i, &c) in counts.iter().enumerate() {
        let split = &details[at..at + c as usize];
        let sum = split
            .iter()
            .map(|q| square(q.map(i64::from)))
            .fold(0u128, u128::saturating_add);
        add_square(&mut squares, first_level + i + 1, sum);
        at += c as usize;
    }
    squares
}

/// Appends the squares of the next run of splits to `all`.
fn merge_squares(all: &mut OctaveSquares, run: OctaveSquares) {
    for (key, sum) in run {
        match all.last_mut() {
            Some((k, s)) if *k == key => *s = s.saturating_add(sum),
            _ => all.push((key, sum)),
        }
    }
}

impl PartialEq for StoredDetails {
    /// Equal details, however they are held.
    fn eq(&self, other: &Self) -> bool {
        self.relaxation == other.relaxation
            && self.base == other.base
            && self.counts == other.counts
            && self.step.to_bits() == other.step.to_bits()
            && self.quantised().ok() == other.quantised().ok()
    }
}

impl StoredDetails {
    /// Details `q · step` (`quantised`, in split order, `counts[k]` of them for split `k`).
    /// Fails unless the counts add up to the details and `step` is a positive power of two.
    pub fn from_quantised(
        relaxation: RelaxationSpec,
        base: Vec<DVec3>,
        counts: Vec<u32>,
        quantised: Vec<[i32; 3]>,
        step: f64,
    ) -> Result<StoredDetails, String> {
        let total: u64 = counts.iter().map(|&c| u64::from(c)).sum();
        if total != quantised.len() as u64 {
            return Err(format!(
                "the counts add up to {total} details, not {}",
                quantised.len()
            ));
        }
        if !(step > 0.0 && step.is_finite() && step.log2().fract() == 0.0) {
            return Err(format!(
                "a detail step of {step} (it must be a power of two)"
            ));
        }
        Ok(StoredDetails {
            relaxation,
            base,
            counts,
            step,
            values: Values::Quantised(quantised),
        })
    }

    /// The details of `n_splits` splits, split `k`'s being `split(k)` (whole multiples of
    /// `step`, a positive power of two), coded as a file stores them: a fifth of their size in
    /// memory, and a `.pyr` writer copies the blocks as they are. The blocks are coded on all
    /// cores.
    pub fn coded<'s>(
        relaxation: RelaxationSpec,
        base: Vec<DVec3>,
        n_splits: usize,
        split: impl Fn(usize) -> &'s [[i32; 3]] + Sync,
        step: f64,
    ) -> Result<StoredDetails, String> {
        use rayon::prelude::*;
        let n_base = base.len();
        let checked = StoredDetails::from_quantised(relaxation, base, vec![], vec![], step)?;
        let n_blocks = n_splits.div_ceil(SPLITS_PER_BLOCK);
        let coded: Vec<(Vec<u32>, usize, Vec<u8>, OctaveSquares)> = (0..n_blocks)
            .into_par_iter()
            .map(|b| {
                let splits = b * SPLITS_PER_BLOCK..((b + 1) * SPLITS_PER_BLOCK).min(n_splits);
                let first_level = n_base + splits.start;
                let counts: Vec<u32> = splits.clone().map(|k| split(k).len() as u32).collect();
                let details: Vec<[i32; 3]> =
                    splits.flat_map(|k| split(k).iter().copied()).collect();
                let block = encode_block(&counts, &details);
                let squares = squares_of(first_level, &counts, &details);
                (counts, details.len(), block, squares)
            })
            .collect();
        let mut counts = Vec::with_capacity(n_splits);
        let mut blocks = CodedBlocks {
            bytes: Vec::with_capacity(coded.iter().map(|c| c.2.len()).sum()),
            blocks: Vec::with_capacity(n_blocks),
            n_details: 0,
            squares: OctaveSquares::new(),
        };
        for (c, n, bytes, squares) in coded {
            let start = blocks.bytes.len();
            blocks.bytes.extend_from_slice(&bytes);
            blocks.blocks.push((c.len(), start..blocks.bytes.len(), 0));
            blocks.n_details += n;
            counts.extend(c);
            merge_squares(&mut blocks.squares, squares);
        }
        Ok(StoredDetails {
            counts,
            values: Values::Coded(blocks),
            ..checked
        })
    }

    /// Total number of details.
    pub fn n_details(&self) -> usize {
        match &self.values {
            Values::Quantised(q) => q.len(),
            Values::Coded(c) => c.n_details,
        }
    }

    /// Calls `f(first, counts, details)` for consecutive runs of splits in split order:
    /// `first` is the run's first split, `counts` its splits' detail counts and `details`
    /// their quantised details. Coded details are decoded a few blocks at a time on all
    /// cores, so that only those blocks are held decoded.
    pub fn for_each_block(
        &self,
        f: impl FnMut(usize, &[u32], &[[i32; 3]]),
    ) -> Result<(), FormatError> {
        self.for_each_block_up_to(usize::MAX, f)
    }

    /// [`Self::for_each_block`] for the runs that hold splits below `n_splits` only (the last
    /// run may hold later splits too): the blocks after them are not decoded.
    pub fn for_each_block_up_to(
        &self,
        n_splits: usize,
        mut f: impl FnMut(usize, &[u32], &[[i32; 3]]),
    ) -> Result<(), FormatError> {
        match &self.values {
            Values::Quantised(q) => {
                let mut at = 0;
                for (b, counts) in self.counts.chunks(SPLITS_PER_BLOCK).enumerate() {
                    if b * SPLITS_PER_BLOCK >= n_splits {
                        break;
                    }
                    let n: usize = counts.iter().map(|&c| c as usize).sum();
                    f(b * SPLITS_PER_BLOCK, counts, &q[at..at + n]);
                    at += n;
                }
                Ok(())
            }
            Values::Coded(coded) => coded.for_each_block(n_splits, &mut f),
        }
    }

    /// All quantised details in split order.
    pub fn quantised(&self) -> Result<std::borrow::Cow<'_, [[i32; 3]]>, FormatError> {
        if let Values::Quantised(q) = &self.values {
            return Ok(std::borrow::Cow::Borrowed(q));
        }
        let mut all = Vec::with_capacity(self.n_details());
        self.for_each_block(|_, _, d| all.extend_from_slice(d))?;
        Ok(std::borrow::Cow::Owned(all))
    }

    /// The details' squares per octave of levels ([`OctaveSquares`]), on a hierarchy of
    /// `self.base.len()` base vertices: kept from the first decoding when the details are
    /// coded, summed now when they are held quantised.
    pub(crate) fn octave_squares(&self) -> std::borrow::Cow<'_, OctaveSquares> {
        match &self.values {
            Values::Coded(c) => std::borrow::Cow::Borrowed(&c.squares),
            Values::Quantised(q) => {
                std::borrow::Cow::Owned(squares_of(self.base.len(), &self.counts, q))
            }
        }
    }

    /// All details in split order, in model units.
    pub fn details(&self) -> Result<Vec<DVec3>, FormatError> {
        let step = self.step;
        Ok(self
            .quantised()?
            .iter()
            .map(|q| DVec3::from_array(q.map(|x| f64::from(x) * step)))
            .collect())
    }
}

impl CodedBlocks {
    /// Decodes the blocks a few at a time on all cores and hands them to `f` in order, up to
    /// the batch that reaches split `n_splits`.
    fn for_each_block(
        &self,
        n_splits: usize,
        f: &mut impl FnMut(usize, &[u32], &[[i32; 3]]),
    ) -> Result<(), FormatError> {
        use rayon::prelude::*;
        let batch = 4 * rayon::current_num_threads().max(1);
        let mut first = 0;
        for blocks in self.blocks.chunks(batch) {
            if first >= n_splits {
                break;
            }
            let decoded: Vec<(Vec<u32>, Vec<[i32; 3]>)> = blocks
                .par_iter()
                .map(|(n, range, at)| {
                    let mut out = Some(Vec::new());
                    let bytes = &self.bytes[range.clone()];
                    let (counts, _) = decode_block(*n, bytes, *at, self.n_details, &mut out, None)?;
                    Ok((counts, out.unwrap_or_default()))
                })
                .collect::<Result<_, FormatError>>()?;
            for (counts, details) in decoded {
                f(first, &counts, &details);
                first += counts.len();
            }
        }
        Ok(())
    }
}

/// A decoded `DETL` section.
#[derive(Clone, Debug)]
pub(crate) struct DetailSection {
    /// The analysis version the details come from.
    pub analysis_version: u8,
    /// CRC-32 of the `BASE` and `SPLT` payloads they were analysed on.
    pub hierarchy_crcs: [u32; 2],
    /// The details and what they were computed with, or why this reader cannot hold them.
    pub stored: Result<StoredDetails, String>,
}

/// The exact power of two `2^e`, for `e` in the normal range.
fn power_of_two(e: i32) -> Option<f64> {
    (-1022..=1023)
        .contains(&e)
        .then(|| f64::from_bits(((e + 1023) as u64) << 52))
}

/// The `DETL` payload of `stored` (details in split order, whole multiples of its step),
/// analysed on the hierarchy whose `BASE` and `SPLT` payloads have checksums
/// `hierarchy_crcs`. `None` when the step is outside the range the format codes.
pub(crate) fn encode_details(
    stored: &StoredDetails,
    hierarchy_crcs: [u32; 2],
) -> Result<Option<Vec<u8>>, FormatError> {
    let step_exp = stored.step.log2() as i32;
    if power_of_two(step_exp) != Some(stored.step) || step_exp > MAX_STEP_EXP {
        return Ok(None);
    }
    let Ok(relaxation) =
        bincode::serde::encode_to_vec(stored.relaxation, bincode::config::standard())
    else {
        return Ok(None);
    };
    let mut out = vec![ANALYSIS_VERSION];
    out.extend(relaxation);
    for crc in hierarchy_crcs {
        out.extend_from_slice(&crc.to_le_bytes());
    }
    out.extend_from_slice(&(step_exp as i16).to_le_bytes());
    put_uvarint(&mut out, stored.counts.len() as u64);
    put_uvarint(&mut out, stored.n_details() as u64);
    for p in &stored.base {
        for x in p.to_array() {
            out.extend_from_slice(&x.to_bits().to_le_bytes());
        }
    }
    match &stored.values {
        // Coded by this coder (a pyramid's, or a file's checked on load): the same bytes.
        Values::Coded(coded) => {
            for (_, range, _) in &coded.blocks {
                put_uvarint(&mut out, range.len() as u64);
                out.extend_from_slice(&coded.bytes[range.clone()]);
            }
        }
        Values::Quantised(_) => stored.for_each_block(|_, counts, details| {
            let block = encode_block(counts, details);
            put_uvarint(&mut out, block.len() as u64);
            out.extend_from_slice(&block);
        })?,
    }
    Ok(Some(out))
}

fn encode_block(counts: &[u32], details: &[[i32; 3]]) -> Vec<u8> {
    let mut w = BitWriter::default();
    let mut ctx = [Context::default(); N_CONTEXTS];
    let mut at = 0;
    for &c in counts {
        w.code(&mut ctx[0], i64::from(c) - 7);
        for (i, d) in details[at..at + c as usize].iter().enumerate() {
            let first = if i == 0 { 1 } else { 4 };
            for (j, &x) in d.iter().enumerate() {
                w.code(&mut ctx[first + j], i64::from(x));
            }
        }
        at += c as usize;
    }
    w.finish()
}

/// Decodes a `DETL` payload for a hierarchy of `n_base` base vertices and `n_splits` splits
/// (from `META`); every count is checked before anything is allocated from it.
pub(crate) fn decode_details(
    mut r: ByteReader<'_>,
    n_base: usize,
    n_splits: usize,
) -> Result<DetailSection, FormatError> {
    let analysis_version = r.array::<1>("detail analysis version")?[0];
    let relaxation = read_relaxation(&mut r)?;
    let hierarchy_crcs = [
        r.u32("checksum of the details' BASE")?,
        r.u32("checksum of the details' SPLT")?,
    ];
    let at = r.offset();
    let step_exp = i32::from(i16::from_le_bytes(r.array("detail step")?));
    // Steps above 2^969 could make `q · step` infinite.
    let step = power_of_two(step_exp)
        .filter(|_| step_exp <= MAX_STEP_EXP)
        .ok_or_else(|| corrupt(at, format!("detail step 2^{step_exp} out of range")))?;
    let at = r.offset();
    let counted = r.count(u64::MAX, "split count of the details")?;
    if counted != n_splits {
        return Err(corrupt(
            at,
            format!("details for {counted} splits in a file of {n_splits}"),
        ));
    }
    // Every detail takes at least 3 bits.
    let max_details = (r.remaining() as u64).saturating_mul(8) / 3;
    let n_details = r.count(max_details, "detail count")?;
    let base = read_base(&mut r, n_base)?;
    let blocks = block_slices(&mut r, n_splits)?;
    let (counts, fit, squares) = check_blocks(&blocks, n_base, n_details)?;
    let stored = fit
        .then(|| StoredDetails {
            relaxation,
            base,
            counts,
            step,
            values: Values::Coded(coded_copy(&blocks, n_details, squares)),
        })
        .ok_or_else(|| "a stored detail is beyond the 32 bits the pyramid keeps".to_string());
    Ok(DetailSection {
        analysis_version,
        hierarchy_crcs,
        stored,
    })
}

/// The blocks copied out of the file, to be decoded when the details are asked for.
fn coded_copy(blocks: &[Block<'_>], n_details: usize, squares: OctaveSquares) -> CodedBlocks {
    let mut bytes = Vec::with_capacity(blocks.iter().map(|b| b.1.len()).sum());
    let blocks = blocks
        .iter()
        .map(|&(n, b, at)| {
            let start = bytes.len();
            bytes.extend_from_slice(b);
            (n, start..bytes.len(), at)
        })
        .collect();
    CodedBlocks {
        bytes,
        blocks,
        n_details,
        squares,
    }
}

fn read_relaxation(r: &mut ByteReader<'_>) -> Result<RelaxationSpec, FormatError> {
    let at = r.offset();
    let head = r
        .clone()
        .take(r.remaining().min(MAX_RELAXATION), "relaxation")?;
    let config = bincode::config::standard().with_limit::<MAX_RELAXATION>();
    let (spec, len): (RelaxationSpec, usize) = bincode::serde::decode_from_slice(head, config)
        .map_err(|e| corrupt(at, format!("relaxation of the details: {e}")))?;
    r.take(len, "relaxation")?;
    if let Some(why) = spec.invalid() {
        return Err(corrupt(at, format!("relaxation of the details: {why}")));
    }
    Ok(spec)
}

fn read_base(r: &mut ByteReader<'_>, n_base: usize) -> Result<Vec<DVec3>, FormatError> {
    let bytes = r.take(n_base.saturating_mul(24), "base signal of the details")?;
    Ok(bytes
        .chunks_exact(24)
        .map(|p| {
            let x = |i: usize| f64::from_le_bytes(p[8 * i..8 * i + 8].try_into().expect("8 bytes"));
            DVec3::new(x(0), x(1), x(2))
        })
        .collect())
}

/// A block of the section: how many splits it holds, its bytes and their file offset.
type Block<'a> = (usize, &'a [u8], u64);

/// The blocks of `n_splits` splits.
fn block_slices<'a>(
    r: &mut ByteReader<'a>,
    n_splits: usize,
) -> Result<Vec<Block<'a>>, FormatError> {
    let mut blocks = Vec::new();
    let mut left = n_splits;
    while left > 0 {
        let n = left.min(SPLITS_PER_BLOCK);
        let len = r.count(r.remaining() as u64, "detail block length")?;
        let at = r.offset();
        blocks.push((n, r.take(len, "detail block")?, at));
        left -= n;
    }
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "bytes after the last detail block"));
    }
    Ok(blocks)
}

/// Decodes the blocks on all cores to check them, keeping only their counts, which must add
/// up to `n_details`, and the details' squares per octave of a hierarchy of `n_base` base
/// vertices; says whether every detail fits 32 bits.
fn check_blocks(
    blocks: &[Block<'_>],
    n_base: usize,
    n_details: usize,
) -> Result<(Vec<u32>, bool, OctaveSquares), FormatError> {
    use rayon::prelude::*;
    let decoded: Vec<(Vec<u32>, bool, OctaveSquares)> = blocks
        .par_iter()
        .enumerate()
        .map(|(b, &(n, bytes, at))| {
            let mut squares = OctaveSquares::new();
            let first_level = n_base.saturating_add(b * SPLITS_PER_BLOCK);
            let sums = Some((first_level, &mut squares));
            let (counts, fit) = decode_block(n, bytes, at, n_details, &mut None, sums)?;
            Ok((counts, fit, squares))
        })
        .collect::<Result<_, FormatError>>()?;
    let total: u64 = decoded
        .iter()
        .flat_map(|b| &b.0)
        .map(|&c| u64::from(c))
        .sum();
    if total != n_details as u64 {
        let end = blocks.last().map_or(0, |b| b.2 + b.1.len() as u64);
        return Err(corrupt(
            end,
            format!("{total} details where the section announces {n_details}"),
        ));
    }
    let fit = decoded.iter().all(|b| b.1);
    let mut counts = Vec::with_capacity(blocks.iter().map(|b| b.0).sum());
    let mut squares = OctaveSquares::new();
    for (c, _, s) in decoded {
        counts.extend(c);
        merge_squares(&mut squares, s);
    }
    Ok((counts, fit, squares))
}

/// One block of `n` splits (no block holds more than `max_details` details): its counts, and
/// whether every detail fits 32 bits. With `out`, the details are appended to it, and then
/// they must fit. With `squares` (the level before the block's first split's, and where to
/// add), the details' squares are added per octave.
fn decode_block(
    n: usize,
    bytes: &[u8],
    at: u64,
    max_details: usize,
    out: &mut Option<Vec<[i32; 3]>>,
    mut squares: Option<(usize, &mut OctaveSquares)>,
) -> Result<(Vec<u32>, bool), FormatError> {
    let mut r = BitReader::new(bytes, at);
    let mut ctx = [Context::default(); N_CONTEXTS];
    let mut counts = Vec::with_capacity(n);
    let mut seen = 0i64;
    let mut fit = true;
    for split in 0..n {
        let c = r.decode(&mut ctx[0])?.saturating_add(7);
        if c < 1 || seen.saturating_add(c) > max_details as i64 {
            return Err(corrupt(at, format!("a split with {c} details")));
        }
        seen += c;
        counts.push(c as u32);
        let mut sum = 0u128;
        for i in 0..c {
            let first = if i == 0 { 1 } else { 4 };
            let mut q = [0i32; 3];
            let mut wide = [0i64; 3];
            for (j, x) in q.iter_mut().enumerate() {
                let v = r.decode(&mut ctx[first + j])?;
                if !(-MAX_QUANTISED < v && v < MAX_QUANTISED) {
                    return Err(corrupt(at, format!("quantised detail {v} out of range")));
                }
                wide[j] = v;
                *x = i32::try_from(v).unwrap_or_else(|_| {
                    fit = false;
                    0
                });
            }
            if squares.is_some() {
                sum = sum.saturating_add(square(wide));
            }
            if let Some(out) = out.as_mut() {
                if !fit {
                    return Err(corrupt(at, "a detail beyond 32 bits"));
                }
                out.push(q);
            }
        }
        if let Some((first_level, squares)) = squares.as_mut() {
            add_square(squares, first_level.saturating_add(split + 1), sum);
        }
    }
    if !r.at_end() {
        return Err(corrupt(at, "bytes after the last detail of a block"));
    }
    Ok((counts, fit))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stored(counts: Vec<u32>, n: usize, step: f64) -> Result<StoredDetails, String> {
        let details = (0..n as i32).map(|i| [i, -i, 2 * i]).collect();
        StoredDetails::from_quantised(RelaxationSpec::default(), vec![], counts, details, step)
    }

    #[test]
    fn quantised_details_need_matching_counts_and_a_power_of_two_step() {
        assert!(stored(vec![7, 8], 15, 0.25).is_ok());
        assert!(stored(vec![7, 8], 14, 0.25).is_err());
        assert!(stored(vec![7, 8], 15, 0.3).is_err());
        assert!(stored(vec![7, 8], 15, 0.0).is_err());
    }

    #[test]
    fn coded_details_decode_to_the_values_they_were_coded_from() {
        let counts: Vec<u32> = (0..3 * SPLITS_PER_BLOCK as u32 + 5)
            .map(|k| 7 + k % 3)
            .collect();
        let n = counts.iter().map(|&c| c as usize).sum();
        let plain = stored(counts, n, 0.5).unwrap();
        let bytes = encode_details(&plain, [1, 2]).unwrap().unwrap();
        let n_splits = plain.counts.len();
        let section = decode_details(ByteReader::new(&bytes, 0), 0, n_splits).unwrap();
        let coded = section.stored.unwrap();
        assert!(matches!(coded.values, Values::Coded(_)));
        assert_eq!(coded, plain);
        assert_eq!(coded.quantised().unwrap(), plain.quantised().unwrap());
        let mut firsts = vec![];
        coded
            .for_each_block(|first, counts, details| {
                let sum: u32 = counts.iter().sum();
                assert_eq!(details.len(), sum as usize);
                firsts.push(first);
            })
            .unwrap();
        assert_eq!(firsts, [0, 4096, 8192, 12288]);
        assert_eq!(encode_details(&coded, [1, 2]).unwrap().unwrap(), bytes);
    }
}
