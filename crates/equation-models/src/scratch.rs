//! A scratch buffer per thread for evaluations: grown to the largest model a thread evaluates,
//! then reused, so that evaluations allocate nothing after the first one on each thread.

use std::cell::RefCell;

thread_local! {
    static SCRATCH: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` on `len` numbers of scratch (of unspecified content): the thread's buffer, or a
/// fresh one if it is in use (a nested call) or gone (the thread is ending).
pub(crate) fn with_scratch<R>(len: usize, mut f: impl FnMut(&mut [f64]) -> R) -> R {
    let result = SCRATCH.try_with(|cell| {
        cell.try_borrow_mut().ok().map(|mut buffer| {
            if buffer.len() < len {
                buffer.resize(len, 0.0);
            }
            f(&mut buffer[..len])
        })
    });
    match result {
        Ok(Some(r)) => r,
        _ => f(&mut vec![0.0; len]),
    }
}
