fn main() -> std::process::ExitCode {
    return_large_blocks_to_the_system();
    meshpyr_cli::main()
}

/// glibc serves blocks below its mmap threshold from heaps it keeps after they are freed, and
/// raises the threshold (up to 32 MiB) each time a mapped block is freed. A scan's pipeline
/// frees many blocks of a few MiB (per-range records, chunks, scratch signals) before it maps
/// the next large one, so those heaps would stay resident beside it. A fixed 1 MiB threshold
/// maps every large block and unmaps it on free: the peak is what is live, not what was.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn return_large_blocks_to_the_system() {
    // SAFETY: `mallopt` only sets an allocator parameter; called before any thread exists.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn return_large_blocks_to_the_system() {}
