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

/// Details given without a step (exact) are quantised with `2^(⌊log2 diagonal⌋ − STEP_BITS)`:
/// at most 2^-STEP_BITS of the diagonal, at least half that.
pub(crate) const STEP_BITS: i32 = 36;

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
#[derive(Clone, Debug, PartialEq)]
pub struct StoredDetails {
    /// The relaxation operator, with its options, the details were analysed with.
    pub relaxation: RelaxationSpec,
    /// The base signal `f^(n0)` (exact).
    pub base: Vec<DVec3>,
    /// Per split, how many details it carries (the new vertex and its ring).
    pub counts: Vec<u32>,
    /// All details in split order, each in its local frame `(t1, t2, n)`.
    pub details: Vec<DVec3>,
    /// The quantisation step of every detail component (model units; 0 for exact values):
    /// each component is within half of it of the analysed one.
    pub step: f64,
}

/// A decoded `DETL` section.
#[derive(Clone, Debug)]
pub(crate) struct DetailSection {
    /// The analysis version the details come from.
    pub analysis_version: u8,
    /// CRC-32 of the `BASE` and `SPLT` payloads they were analysed on.
    pub hierarchy_crcs: [u32; 2],
    /// The details (dequantised) and what they were computed with.
    pub stored: StoredDetails,
}

/// The exact power of two `2^e`, for `e` in the normal range.
fn power_of_two(e: i32) -> Option<f64> {
    (-1022..=1023)
        .contains(&e)
        .then(|| f64::from_bits(((e + 1023) as u64) << 52))
}

/// The quantisation step the writer uses for a mesh of bounding-box diagonal `diagonal`.
pub(crate) fn step_exponent(diagonal: f64) -> i32 {
    let e = if diagonal > 0.0 && diagonal.is_finite() {
        diagonal.log2().floor() as i32
    } else {
        0
    };
    (e - STEP_BITS).clamp(-1022, MAX_STEP_EXP)
}

/// The `DETL` payload of `stored` (details in split order), quantised with its step if it has
/// one (a power of two, as [`StoredDetails::of`] gives), else with `2^step_exp`, analysed on the hierarchy whose `BASE` and `SPLT` payloads have checksums
/// `hierarchy_crcs`. `None` when a detail is not finite or too large to quantise (the file is
/// then written without the section).
pub(crate) fn encode_details(
    stored: &StoredDetails,
    step_exp: i32,
    hierarchy_crcs: [u32; 2],
) -> Option<Vec<u8>> {
    let step_exp = if stored.step > 0.0 {
        stored.step.log2() as i32
    } else {
        step_exp
    };
    let step = power_of_two(step_exp).filter(|&s| stored.step == 0.0 || s == stored.step)?;
    let quantised = quantise(&stored.details, step)?;
    let mut out = vec![ANALYSIS_VERSION];
    out.extend(bincode::serde::encode_to_vec(stored.relaxation, bincode::config::standard()).ok()?);
    for crc in hierarchy_crcs {
        out.extend_from_slice(&crc.to_le_bytes());
    }
    out.extend_from_slice(&(step_exp as i16).to_le_bytes());
    put_uvarint(&mut out, stored.counts.len() as u64);
    put_uvarint(&mut out, stored.details.len() as u64);
    for p in &stored.base {
        for x in p.to_array() {
            out.extend_from_slice(&x.to_bits().to_le_bytes());
        }
    }
    let mut at = 0;
    for counts in stored.counts.chunks(SPLITS_PER_BLOCK) {
        let n: usize = counts.iter().map(|&c| c as usize).sum();
        let block = encode_block(counts, &quantised[at..at + n]);
        at += n;
        put_uvarint(&mut out, block.len() as u64);
        out.extend_from_slice(&block);
    }
    Some(out)
}

/// Each component as a multiple of `step`; `None` if one is not finite or beyond 2^53 steps
/// (where `q · step` would no longer be exact).
fn quantise(details: &[DVec3], step: f64) -> Option<Vec<[i64; 3]>> {
    const LIMIT: f64 = MAX_QUANTISED as f64;
    details
        .iter()
        .map(|d| {
            let q = d.to_array().map(|x| (x / step).round());
            q.iter()
                .all(|x| x.abs() < LIMIT)
                .then(|| q.map(|x| x as i64))
        })
        .collect()
}

fn encode_block(counts: &[u32], details: &[[i64; 3]]) -> Vec<u8> {
    let mut w = BitWriter::default();
    let mut ctx = [Context::default(); N_CONTEXTS];
    let mut at = 0;
    for &c in counts {
        w.code(&mut ctx[0], i64::from(c) - 7);
        for (i, d) in details[at..at + c as usize].iter().enumerate() {
            let first = if i == 0 { 1 } else { 4 };
            for (j, &x) in d.iter().enumerate() {
                w.code(&mut ctx[first + j], x);
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
    let (counts, details) = decode_blocks(&blocks, n_details, step)?;
    Ok(DetailSection {
        analysis_version,
        hierarchy_crcs,
        stored: StoredDetails {
            relaxation,
            base,
            counts,
            details,
            step,
        },
    })
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

/// Decodes the blocks on all cores; the counts must add up to `n_details`.
fn decode_blocks(
    blocks: &[Block<'_>],
    n_details: usize,
    step: f64,
) -> Result<(Vec<u32>, Vec<DVec3>), FormatError> {
    use rayon::prelude::*;
    let decoded: Vec<(Vec<u32>, Vec<DVec3>)> = blocks
        .par_iter()
        .map(|&(n, bytes, at)| decode_block(n, bytes, at, n_details, step))
        .collect::<Result<_, _>>()?;
    let total: usize = decoded.iter().map(|b| b.1.len()).sum();
    if total != n_details {
        let end = blocks.last().map_or(0, |b| b.2 + b.1.len() as u64);
        return Err(corrupt(
            end,
            format!("{total} details where the section announces {n_details}"),
        ));
    }
    let mut counts = Vec::with_capacity(blocks.iter().map(|b| b.0).sum());
    let mut details = Vec::with_capacity(n_details);
    for (c, d) in decoded {
        counts.extend(c);
        details.extend(d);
    }
    Ok((counts, details))
}

/// One block of `n` splits; no block holds more than `max_details` details.
fn decode_block(
    n: usize,
    bytes: &[u8],
    at: u64,
    max_details: usize,
    step: f64,
) -> Result<(Vec<u32>, Vec<DVec3>), FormatError> {
    let mut r = BitReader::new(bytes, at);
    let mut ctx = [Context::default(); N_CONTEXTS];
    let mut counts = Vec::with_capacity(n);
    let mut details = Vec::new();
    for _ in 0..n {
        let c = r.decode(&mut ctx[0])?.saturating_add(7);
        if c < 1 || (details.len() as i64).saturating_add(c) > max_details as i64 {
            return Err(corrupt(at, format!("a split with {c} details")));
        }
        counts.push(c as u32);
        for i in 0..c {
            let first = if i == 0 { 1 } else { 4 };
            let mut q = [0.0; 3];
            for (j, x) in q.iter_mut().enumerate() {
                let v = r.decode(&mut ctx[first + j])?;
                if !(-MAX_QUANTISED < v && v < MAX_QUANTISED) {
                    return Err(corrupt(at, format!("quantised detail {v} out of range")));
                }
                *x = v as f64 * step;
            }
            details.push(DVec3::from_array(q));
        }
    }
    if !r.at_end() {
        return Err(corrupt(at, "bytes after the last detail of a block"));
    }
    Ok((counts, details))
}
