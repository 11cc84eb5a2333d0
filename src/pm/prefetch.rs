//! Software prefetching for the loops that visit a mesh in an order unrelated to its memory
//! layout: decimation (edges in cost order) and split replay (splits in PM order). Nearly every
//! record they read is a cache miss, and each one's records form a chain of dependent loads,
//! so the hardware prefetcher cannot help; hinting the records of the items a few places ahead
//! while the current one is processed overlaps those misses (the gain is in
//! `docs/performance.md`, with the simplify timings).

/// A cache hint for the line at `p`. The address may be anything: it is never dereferenced.
#[inline(always)]
pub(crate) fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `_mm_prefetch` only needs SSE, which every x86_64 CPU has; a prefetch is a hint
    // that reads nothing into the program and never faults, whatever the address.
    unsafe {
        core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(p as *const i8)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
