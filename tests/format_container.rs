//! The `.pyr` container and varint primitives: round trips and damage detection.

use meshpyr::format::FormatError;
use meshpyr::format::container::{Container, REQUIRED, Section, write_container};
use meshpyr::format::varint::{ByteReader, put_ivarint, put_uvarint};
use proptest::prelude::*;

fn sample() -> Vec<u8> {
    write_container(
        1,
        0,
        &[
            Section {
                tag: *b"HEAD",
                flags: REQUIRED,
                bytes: b"hello".to_vec(),
            },
            Section {
                tag: *b"XTRA",
                flags: 0,
                bytes: vec![7; 100],
            },
        ],
    )
}

#[test]
fn container_round_trip() {
    let bytes = sample();
    let c = Container::parse(&bytes).unwrap();
    assert_eq!((c.major, c.minor), (1, 0));
    assert!(!c.is_truncated());
    let mut s = c.section(*b"HEAD").unwrap().unwrap();
    assert_eq!(s.take(5, "x").unwrap(), b"hello");
    assert!(c.section(*b"NONE").unwrap().is_none());
    assert_eq!(c.unknown_required(&[*b"HEAD"]), Vec::<String>::new());
    assert_eq!(c.unknown_required(&[]), vec!["HEAD".to_string()]);
}

#[test]
fn every_bit_flip_is_detected_or_harmless() {
    let bytes = sample();
    for i in 0..bytes.len() {
        for bit in 0..8 {
            let mut b = bytes.clone();
            b[i] ^= 1 << bit;
            let ok = Container::parse(&b).and_then(|c| {
                c.section(*b"HEAD")?;
                c.section(*b"XTRA")?;
                Ok(())
            });
            assert!(ok.is_err(), "flip at byte {i} bit {bit} went unnoticed");
        }
    }
}

#[test]
fn truncation_is_reported() {
    let bytes = sample();
    for n in 0..bytes.len() {
        let r = Container::parse(&bytes[..n]).and_then(|c| {
            c.section(*b"HEAD")?;
            c.section(*b"XTRA")?;
            Ok(())
        });
        assert!(r.is_err(), "prefix of {n} bytes accepted");
    }
    // A file cut inside the last section still yields the first.
    let cut = &bytes[..bytes.len() - 10];
    let c = Container::parse(cut).unwrap();
    assert!(c.is_truncated());
    assert!(c.section(*b"HEAD").unwrap().is_some());
    assert!(matches!(
        c.section(*b"XTRA"),
        Err(FormatError::Truncated { .. })
    ));
    assert_eq!(c.section_prefix(*b"XTRA").unwrap().remaining(), 90);
}

#[test]
fn overlong_varints_are_errors() {
    let mut r = ByteReader::new(&[0xff; 11], 0);
    assert!(r.uvarint("v").is_err());
    let mut r = ByteReader::new(
        &[0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x02],
        0,
    );
    assert!(r.uvarint("v").is_err());
    let mut r = ByteReader::new(&[0x80], 0);
    assert!(matches!(r.uvarint("v"), Err(FormatError::Truncated { .. })));
    let mut buf = Vec::new();
    put_uvarint(&mut buf, 1000);
    let mut r = ByteReader::new(&buf, 0);
    assert!(r.count(999, "n").is_err());
}

#[test]
fn short_varints_decode_and_truncate_like_long_ones() {
    // One-, two- and three-byte codes take a fast path; they must agree with the general
    // decoder on values, lengths and truncation.
    let edges = [
        127,
        128,
        16383,
        16384,
        (1 << 21) - 1,
        1 << 21,
        (1 << 28) - 1,
        1 << 28,
    ];
    for v in (0..1u64 << 22).step_by(89).chain(edges) {
        let mut buf = Vec::new();
        put_uvarint(&mut buf, v);
        buf.push(0x55);
        let mut r = ByteReader::new(&buf, 0);
        assert_eq!(r.uvarint("v").unwrap(), v);
        assert_eq!(r.remaining(), 1);
        for cut in 0..buf.len() - 1 {
            let mut r = ByteReader::new(&buf[..cut], 0);
            assert!(matches!(r.uvarint("v"), Err(FormatError::Truncated { .. })));
        }
    }
}

proptest! {
    #[test]
    fn varints_round_trip(u in any::<u64>(), i in any::<i64>()) {
        let mut buf = Vec::new();
        put_uvarint(&mut buf, u);
        put_ivarint(&mut buf, i);
        let mut r = ByteReader::new(&buf, 0);
        prop_assert_eq!(r.uvarint("u").unwrap(), u);
        prop_assert_eq!(r.ivarint("i").unwrap(), i);
        prop_assert!(r.is_empty());
    }

    #[test]
    fn garbage_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        if let Ok(c) = Container::parse(&bytes) {
            for s in c.sections.clone() {
                let _ = c.section(s.tag);
                let _ = c.section_prefix(s.tag);
            }
        }
    }
}
