//! Scratch buffers per thread for evaluations (numbers, and intervals for the enclosures): grown
//! to the largest model a thread evaluates, then reused, so that evaluations allocate nothing
//! after the first one on each thread.

use std::cell::RefCell;
use std::thread::LocalKey;

use intervals::Interval;

thread_local! {
    static SCRATCH: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    static INTERVALS: RefCell<Vec<Interval>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` on `len` entries of the thread's buffer `key` (of unspecified content), or on a fresh
/// one if it is in use (a nested call) or gone (the thread is ending).
fn with_buffer<T: Copy, R>(
    key: &'static LocalKey<RefCell<Vec<T>>>,
    len: usize,
    zero: T,
    mut f: impl FnMut(&mut [T]) -> R,
) -> R {
    let result = key.try_with(|cell| {
        cell.try_borrow_mut().ok().map(|mut buffer| {
            if buffer.len() < len {
                buffer.resize(len, zero);
            }
            f(&mut buffer[..len])
        })
    });
    match result {
        Ok(Some(r)) => r,
        _ => f(&mut vec![zero; len]),
    }
}

/// `len` numbers of scratch (see [`with_buffer`]).
pub(crate) fn with_scratch<R>(len: usize, f: impl FnMut(&mut [f64]) -> R) -> R {
    with_buffer(&SCRATCH, len, 0.0, f)
}

/// `len` intervals of scratch, for the enclosures.
pub(crate) fn with_interval_scratch<R>(len: usize, f: impl FnMut(&mut [Interval]) -> R) -> R {
    with_buffer(&INTERVALS, len, Interval::ZERO, f)
}
