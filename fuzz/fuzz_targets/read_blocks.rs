#![no_main]
//! Fuzzes the readers of a partitioned build's task files (`formats/blocks.md`): every reader
//! on arbitrary bytes, as given and with their checksums fixed, returns without panicking
//! (`meshpyr::fuzzing::fuzz_read_block_file`).

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    meshpyr::fuzzing::fuzz_read_block_file(data);
});
