#![no_main]
//! Fuzzes the off reader: parse, and on success write → re-read → write must be stable.

use libfuzzer_sys::fuzz_target;
use meshpyr::fuzzing::fuzz_read;
use meshpyr::io::MeshFormat;

fuzz_target!(|data: &[u8]| {
    fuzz_read(MeshFormat::Off, data);
});
