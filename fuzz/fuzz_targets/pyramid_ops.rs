//! Bytes → a small (possibly degenerate) mesh, its detail pyramid, filters and edits; the
//! analysis and synthesis invariants are checked on 1 and 3 threads (see
//! `meshpyr::fuzzing::fuzz_pyramid`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    meshpyr::fuzzing::fuzz_pyramid(data);
});
