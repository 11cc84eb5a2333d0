//! Entry points of the fuzz targets (`fuzz/fuzz_targets/`) and of the tests that replay their
//! corpora. Hidden from the documentation and not part of the API: each is a thin public door to
//! a harness that lives, with its documentation, next to the code it exercises.
//!
//! Every function panics only on a violated invariant (that is how the fuzzer reports a bug),
//! never because the input is malformed.

use crate::io::MeshFormat;

/// Body of the `read_obj`, `read_ply`, `read_off` and `read_stl` targets: parses `bytes` as
/// `format` and, when that succeeds, checks that write → read → write gives identical bytes in
/// every encoding of the format.
pub fn fuzz_read(format: MeshFormat, bytes: &[u8]) {
    crate::io::fuzz_read(format, bytes)
}

/// Body of the `read_pyr` target: every `.pyr` reader on arbitrary bytes (as given and with
/// their checksums fixed) returns without panicking, and whatever decodes re-encodes stably.
pub fn fuzz_read_pyr(data: &[u8]) {
    crate::format::fuzz_read_pyr(data, &crate::pyramid::fuzz_loaded_pyr)
}

/// `bytes` with every checksum of the `.pyr` container recomputed where the structure can be
/// followed, so that mutated inputs reach the decoders behind the checksums.
pub fn fix_checksums(bytes: &[u8]) -> Vec<u8> {
    crate::format::fix_checksums(bytes)
}

/// Body of the `read_blocks` target: every reader of the task files of a partitioned build run
/// through files (`formats/blocks.md`) on arbitrary bytes, as given and with their checksums
/// fixed, returns an error or a value and never panics.
pub fn fuzz_read_block_file(data: &[u8]) {
    crate::pm::fuzz_read_block_file(data)
}

/// Body of the `pm_ops` target: a small mesh, progressive-mesh build options and a sequence of
/// collapses, splits and level jumps from `data`, with every invariant checked after each step.
pub fn fuzz_operations(data: &[u8]) {
    crate::pm::fuzz_operations(data)
}

/// Body of the `pyramid_ops` target: a small mesh from `data`, its detail pyramid, filters and
/// edits, with analysis and synthesis checked for exactness and thread-count independence.
pub fn fuzz_pyramid(data: &[u8]) {
    crate::pyramid::fuzz_pyramid(data)
}
