//! A cache hint for passes that walk a large array in order.

/// Elements ahead of the one being processed that a pass over the G-buffer prefetches:
/// eight 120-byte entries, ≈ 1 kB or a few hundred cycles of per-pixel shading, enough
/// to cover a miss to memory.
pub const PREFETCH_AHEAD: usize = 8;

/// Asks the CPU to bring the cache line holding `slice[index]` close to the core, so
/// that a loop walking `slice` in order does not wait on each element's first load (the
/// G-buffer is ≈ 58 MB at 800×600, far beyond the caches). A hint only: it changes no
/// value; nothing happens for an index past the end, or off x86-64.
///
/// Written by hand: `std` has no stable prefetch, and the intrinsic is one instruction.
#[inline(always)]
pub fn prefetch<T>(slice: &[T], index: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(item) = slice.get(index) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let address = std::ptr::from_ref(item).cast::<i8>();
        #[expect(
            unsafe_code,
            reason = "the prefetch intrinsic is an unsafe fn taking a raw pointer"
        )]
        // SAFETY: `address` points into a live element of `slice`, and a prefetch never
        // reads memory architecturally nor faults; SSE (which has it) is part of x86-64.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(address)
        };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (slice, index);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_prefetch_past_the_end_or_of_an_empty_slice_is_harmless() {
        let v = vec![1u64, 2, 3];
        for i in [0, 2, 3, 1000, usize::MAX] {
            prefetch(&v, i);
        }
        prefetch::<u64>(&[], 0);
        assert_eq!(v, [1, 2, 3]);
    }
}
