//! Bytes → a small mesh, PM build options and a sequence of collapse / split / level-jump
//! operations; every invariant is checked after every step (see `meshpyr::pm::fuzz_operations`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    meshpyr::pm::fuzz_operations(data);
});
