//! Bytes → a small mesh, PM build options and a sequence of collapse / split / level-jump
//! operations; every invariant is checked after every step (see
//! `meshpyr::fuzzing::fuzz_operations`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    meshpyr::fuzzing::fuzz_operations(data);
});
