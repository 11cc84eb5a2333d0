//! Replays the committed `read_blocks` fuzz corpus (task files of a partitioned build, and any
//! crash reproducers) through the library harness, so that `cargo test` checks that no reader
//! of those files panics, without cargo-fuzz.

mod common;

#[test]
fn replay_read_blocks_corpus() {
    let n = common::replay_fuzz_corpus("read_blocks", meshpyr::fuzzing::fuzz_read_block_file);
    assert!(n > 0, "no read_blocks corpus found");
}

#[test]
fn fixed_byte_patterns() {
    for data in common::byte_patterns(64, 200) {
        meshpyr::fuzzing::fuzz_read_block_file(&data);
    }
}

/// Every truncation and a spread of flipped bytes of every corpus file: the readers refuse
/// them or read them, and never panic (the harness also reads each with its checksums fixed).
#[test]
fn truncated_and_flipped_task_files_never_panic_a_reader() {
    let dir = common::library_dir().join("fuzz/corpus/read_blocks");
    for entry in std::fs::read_dir(dir).unwrap() {
        let good = std::fs::read(entry.unwrap().path()).unwrap();
        for n in (0..good.len()).step_by(7) {
            meshpyr::fuzzing::fuzz_read_block_file(&good[..n]);
        }
        for i in (0..good.len()).step_by(5) {
            let mut bad = good.clone();
            bad[i] ^= 0x5a;
            meshpyr::fuzzing::fuzz_read_block_file(&bad);
        }
    }
}
