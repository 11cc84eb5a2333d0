#![no_main]
//! Fuzzes the `.pyr` reader: full decode, progressive level reads, and on success
//! encode → decode → encode must be stable (`meshpyr::fuzzing::fuzz_read_pyr`).

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    meshpyr::fuzzing::fuzz_read_pyr(data);
});
