//! The extension's global allocator: the system's, with every block of at least 4 KiB aligned
//! to 64 bytes (a cache line). The batch's output buffers are such blocks, and JAX (XLA) takes
//! a CPU buffer without a copy only at that alignment (`socnav.jax`'s views); Arrow asks the
//! same. Smaller blocks keep the system's alignment, so the many small allocations cost nothing
//! more.

use std::alloc::{GlobalAlloc, Layout, System};
use std::ptr;

/// Alignment of the large blocks, bytes.
pub const ALIGN: usize = 64;
/// Blocks of this many bytes or more are aligned to [`ALIGN`].
pub const LARGE: usize = 4096;

/// The system allocator with large blocks aligned to [`ALIGN`] (see the module docs).
pub struct CacheLineAligned;

/// The layout a block of `layout` is allocated with: the same size, its alignment raised to
/// [`ALIGN`] when it is large. A function of the requested layout alone, so that `dealloc` and
/// `realloc` find the layout `alloc` used.
fn adjusted(layout: Layout) -> Layout {
    if layout.size() < LARGE || layout.align() >= ALIGN {
        return layout;
    }
    // Fails only when the size rounded up to 64 would pass isize::MAX, which no allocation of
    // that size could have satisfied anyway; the system's own alignment then stands.
    layout.align_to(ALIGN).unwrap_or(layout)
}

// SAFETY: every block is allocated, grown and freed by `System` with the layout `adjusted`
// gives for its current size, which `System` requires; the size is never changed by it.
unsafe impl GlobalAlloc for CacheLineAligned {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's layout has a non-zero size; `adjusted` keeps the size.
        unsafe { System.alloc(adjusted(layout)) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as `alloc`.
        unsafe { System.alloc_zeroed(adjusted(layout)) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated here with `adjusted(layout)`.
        unsafe { System.dealloc(ptr, adjusted(layout)) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = adjusted(layout);
        let Ok(requested) = Layout::from_size_align(new_size, layout.align()) else {
            return ptr::null_mut();
        };
        let new = adjusted(requested);
        if new.align() == old.align() {
            // SAFETY: `ptr` was allocated with `old`, whose alignment the new size keeps.
            return unsafe { System.realloc(ptr, old, new_size) };
        }
        // The block crosses `LARGE`: its alignment changes, so move it.
        // SAFETY: `new` has a non-zero size (it is at least as large as the caller's new size).
        let fresh = unsafe { System.alloc(new) };
        if !fresh.is_null() {
            // SAFETY: both blocks hold at least the smaller size and do not overlap; `ptr` was
            // allocated with `old`.
            unsafe {
                ptr::copy_nonoverlapping(ptr, fresh, layout.size().min(new_size));
                System.dealloc(ptr, old);
            }
        }
        fresh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_blocks_are_cache_line_aligned_small_ones_as_asked() {
        let big: Vec<f32> = vec![0.0; LARGE];
        assert_eq!(big.as_ptr() as usize % ALIGN, 0);
        let mut grown: Vec<u8> = Vec::with_capacity(8);
        grown.extend(std::iter::repeat_n(7u8, 3 * LARGE));
        assert_eq!(grown.as_ptr() as usize % ALIGN, 0);
        assert!(grown.iter().all(|&b| b == 7));
        grown.truncate(10);
        grown.shrink_to_fit();
        assert_eq!(grown, vec![7u8; 10]);
        assert_eq!(adjusted(Layout::new::<u64>()), Layout::new::<u64>());
    }
}
