//! Replays the committed `pyramid_ops` fuzz corpus (and any crash reproducers) through the
//! library harness, so its invariants are checked by `cargo test` without cargo-fuzz.

mod common;

#[test]
fn replay_pyramid_ops_corpus() {
    let n = common::replay_fuzz_corpus("pyramid_ops", meshpyr::fuzzing::fuzz_pyramid);
    assert!(n > 0, "no pyramid_ops corpus found");
}

#[test]
fn fixed_byte_patterns() {
    for data in common::byte_patterns(64, 300) {
        meshpyr::fuzzing::fuzz_pyramid(&data);
    }
}
