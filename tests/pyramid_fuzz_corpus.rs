//! Replays the committed `pyramid_ops` fuzz corpus (and any crash reproducers) through the
//! library harness, so its invariants are checked by `cargo test` without cargo-fuzz.

use std::path::Path;

#[test]
fn replay_pyramid_ops_corpus() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut n = 0;
    for dir in ["corpus/pyramid_ops", "regressions/pyramid_ops"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        let mut files: Vec<_> = entries.filter_map(|e| e.ok()).map(|e| e.path()).collect();
        files.sort();
        for f in files {
            let data = std::fs::read(&f).unwrap();
            meshpyr::pyramid::fuzz_pyramid(&data);
            n += 1;
        }
    }
    assert!(n > 0, "no pyramid_ops corpus found");
}

#[test]
fn fixed_byte_patterns() {
    for seed in 0u32..64 {
        let data: Vec<u8> = (0..300u32)
            .map(|i| (i.wrapping_mul(2654435761).wrapping_add(seed * 97) >> 7) as u8)
            .collect();
        meshpyr::pyramid::fuzz_pyramid(&data);
    }
}
