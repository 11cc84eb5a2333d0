//! Replays the committed `pm_ops` fuzz corpus (and any crash reproducers) through the library
//! harness, so the fuzz invariants are checked by `cargo test` without cargo-fuzz.

mod common;

#[test]
fn replay_pm_ops_corpus() {
    let n = common::replay_fuzz_corpus("pm_ops", meshpyr::fuzzing::fuzz_operations);
    assert!(n > 0, "no pm_ops corpus found");
}

#[test]
fn fixed_byte_patterns() {
    for data in common::byte_patterns(64, 200) {
        meshpyr::fuzzing::fuzz_operations(&data);
    }
}
