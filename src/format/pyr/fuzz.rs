//! The `read_pyr` fuzz target's body, and the checksum repair that lets mutated files reach
//! the decoders behind the checksums.

use crate::format::container::Container;

use super::{
    FileDetails, PyrData, SPLT, decode, encode, encode_with_details, read_level, read_level_within,
};

/// `bytes` with every checksum (header, sections, `SPLT` blocks) recomputed, where the
/// structure can be followed. Lets the fuzzer reach the decoders behind the checksums, which
/// random mutations almost never get past.
pub(crate) fn fix_checksums(bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let Ok(c) = Container::parse_unchecked(bytes) else {
        return out;
    };
    for (k, e) in c.sections.iter().enumerate() {
        let (start, len) = (e.offset as usize, e.length as usize);
        let Some(end) = start.checked_add(len).filter(|&x| x <= out.len()) else {
            continue;
        };
        if e.tag == SPLT {
            let mut at = start;
            while at + 12 <= end {
                let plen = u32::from_le_bytes([out[at + 4], out[at + 5], out[at + 6], out[at + 7]])
                    as usize;
                let Some(pend) = (at + 12).checked_add(plen).filter(|&x| x <= end) else {
                    break;
                };
                let crc = crc32fast::hash(&out[at + 12..pend]);
                out[at + 8..at + 12].copy_from_slice(&crc.to_le_bytes());
                at = pend;
            }
        }
        let crc = crc32fast::hash(&out[start..end]);
        let entry = 24 + 32 * k + 24;
        out[entry..entry + 4].copy_from_slice(&crc.to_le_bytes());
    }
    let table_end = 24 + 32 * c.sections.len();
    let mut h = crc32fast::Hasher::new();
    h.update(&out[..20]);
    h.update(&out[24..table_end]);
    let crc = h.finalize();
    out[20..24].copy_from_slice(&crc.to_le_bytes());
    out
}

/// Body of the `read_pyr` fuzz target: every reader on arbitrary bytes must return, never
/// panic; whatever decodes must re-encode to a file that decodes to the same data. The input
/// is tried as is and with its checksums fixed ([`fix_checksums`]). A file whose stored
/// details fit it is handed to `loaded` afterwards (the layers above try it as a pyramid).
pub(crate) fn fuzz_read_pyr(data: &[u8], loaded: &dyn Fn(PyrData)) {
    fuzz_one(data, loaded);
    let fixed = fix_checksums(data);
    if fixed != data {
        fuzz_one(&fixed, loaded);
    }
}

fn fuzz_one(data: &[u8], loaded: &dyn Fn(PyrData)) {
    let _ = read_level(data, None);
    let _ = read_level(data, Some(5));
    let _ = read_level_within(data, 20);
    if let Ok(d) = decode(data)
        && let Ok((again, _)) = encode(&d.input, &d.pm, &d.info)
    {
        let Ok(d2) = decode(&again) else {
            panic!("re-encoded file does not decode");
        };
        assert_eq!(d2.input, d.input);
        assert_eq!(d2.pm.splits(), d.pm.splits());
        let Ok((third, _)) = encode(&d2.input, &d2.pm, &d2.info) else {
            panic!("cannot re-encode");
        };
        assert!(third == again, "encode is not idempotent");
    }
    if let Ok(d) = decode(data) {
        // The level replay of a textured file's corners (`OPTS`, `CRNR`): an error, never a
        // panic, whatever the records say.
        let _ = d.level_mesh(d.pm.n_base_vertices());
        fuzz_details(d, loaded);
    }
}

/// A file whose `DETL` section decoded and fits its hierarchy: a re-encoding that keeps the
/// details, then `loaded`.
fn fuzz_details(d: PyrData, loaded: &dyn Fn(PyrData)) {
    let FileDetails::Stored(stored) = &d.details else {
        return;
    };
    let Ok((again, _)) = encode_with_details(&d.input, &d.pm, &d.info, Some(stored)) else {
        return;
    };
    let Ok(d2) = decode(&again) else {
        panic!("re-encoded file with details does not decode");
    };
    let FileDetails::Stored(kept) = &d2.details else {
        panic!("re-encoded details do not fit their own file");
    };
    let Ok((third, _)) = encode_with_details(&d2.input, &d2.pm, &d2.info, Some(kept)) else {
        panic!("cannot re-encode the details");
    };
    assert!(third == again, "encoding details is not idempotent");
    loaded(d);
}
