//! A global allocator that forwards to the system allocator and counts the allocations
//! (`alloc`, `alloc_zeroed`, `realloc`) made by the current thread while [`count`] runs: the
//! workspace's tests that hot paths (a filter step, an SDP solve) allocate nothing after setup.
//!
//! ```ignore
//! #[global_allocator]
//! static GLOBAL: counting_allocator::Counting = counting_allocator::Counting;
//!
//! let (result, allocations) = counting_allocator::count(|| filter.step(&model, &u, &y));
//! assert_eq!(allocations, 0);
//! ```
//!
//! Only allocations of the calling thread inside [`count`] are counted, so other test threads
//! do not disturb a measurement.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// The counting allocator; install it with `#[global_allocator]` in a test binary.
#[derive(Debug, Clone, Copy, Default)]
pub struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    /// This thread's allocations while counting.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
    /// The largest request (bytes) this thread made while counting, since its last [`measure`].
    static LARGEST: Cell<usize> = const { Cell::new(0) };
    /// The bytes this thread requested while counting, since its last [`measure`].
    static BYTES: Cell<usize> = const { Cell::new(0) };
}

fn note(size: usize) {
    // `try_with`: the thread-local may be gone while a thread shuts down.
    if COUNTING.try_with(|c| c.get()).unwrap_or(false) {
        let _ = ALLOCATIONS.try_with(|a| a.set(a.get() + 1));
        let _ = LARGEST.try_with(|l| l.set(l.get().max(size)));
        let _ = BYTES.try_with(|b| b.set(b.get().saturating_add(size)));
    }
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: same contract as ours.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as ours.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: same contract as ours.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: same contract as ours.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Runs `f` and returns its result with the number of allocations the current thread made
/// meanwhile (0 unless [`Counting`] is the global allocator).
pub fn count<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let before = ALLOCATIONS.with(Cell::get);
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (r, ALLOCATIONS.with(Cell::get) - before)
}

/// What [`measure`] saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Usage {
    /// Allocations (and reallocations) made.
    pub allocations: usize,
    /// The largest single request in bytes: a bound on what one buffer took, so that a test can
    /// show an input was refused before anything was allocated for it.
    pub largest: usize,
    /// The bytes of all requests together (a reallocation counts its new size): a bound on the
    /// memory that `f` took at its peak.
    pub bytes: usize,
}

/// Runs `f` and returns its result with the current thread's [`Usage`] meanwhile.
pub fn measure<R>(f: impl FnOnce() -> R) -> (R, Usage) {
    LARGEST.with(|l| l.set(0));
    BYTES.with(|b| b.set(0));
    let (r, allocations) = count(f);
    (r, Usage { allocations, largest: LARGEST.with(Cell::get), bytes: BYTES.with(Cell::get) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[global_allocator]
    static GLOBAL: Counting = Counting;

    #[test]
    fn counts_this_threads_allocations_only_inside_count() {
        let (v, n) = count(|| vec![1u8; 100]);
        assert_eq!(n, 1);
        let (_, n) = count(|| {
            let mut w = Vec::with_capacity(1);
            w.extend_from_slice(&v);
            w
        });
        assert_eq!(n, 2, "allocation and one growth");
        let (x, n) = count(|| v.iter().map(|&b| u32::from(b)).sum::<u32>());
        assert_eq!((x, n), (100, 0));
        // Another thread's allocations are not counted: spawning costs this thread the same
        // whether the spawned thread allocates or not.
        let spawn = |allocs: usize| {
            count(|| {
                std::thread::scope(|s| {
                    s.spawn(move || (0..allocs).map(|i| vec![0u8; i + 1].len()).sum::<usize>()).join().unwrap_or(0)
                })
            })
            .1
        };
        assert_eq!(spawn(0), spawn(1000));
    }

    #[test]
    fn measure_reports_the_largest_request() {
        let (_, usage) = measure(|| (vec![0u8; 10], vec![0u64; 1000]));
        assert_eq!(usage, Usage { allocations: 2, largest: 8000, bytes: 8010 });
        let (_, usage) = measure(|| 1 + 1);
        assert_eq!(usage, Usage { allocations: 0, largest: 0, bytes: 0 });
    }
}
