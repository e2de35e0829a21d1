//! No heap allocation when the EKF evaluates the truck model: `f`, `h` and both Jacobians write
//! into the caller's buffers (a counting global allocator, counting only on this test's thread).
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

use models::{DifferentiableModel, DiscreteModel};
use nalgebra::{DMatrix, DVector};
use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

fn note() {
    if COUNTING.with(|c| c.get()) {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    }
}

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: same contract as ours.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as ours.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: same contract as ours.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        // SAFETY: same contract as ours.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn count<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (r, ALLOCATIONS.load(Ordering::Relaxed) - before)
}

#[test]
fn model_evaluations_do_not_allocate() {
    let model = TruckEkfModel::paper(TruckParams::digest_preset()).unwrap();
    let x = DVector::from_vec(vec![19.44, 0.15, 0.06]);
    let mut input = TruckInput::free_rolling(0.02, 19.44, 0.52);
    input.omega[2..].iter_mut().for_each(|w| *w *= 1.004);
    let u = input.to_dvector();
    let (mut fx, mut hx) = (DVector::zeros(3), DVector::zeros(3));
    let (mut fj, mut hj) = (DMatrix::zeros(3, 3), DMatrix::zeros(3, 3));
    let (r, n) = count(|| {
        for _ in 0..100 {
            model.f(&x, &u, &mut fx)?;
            model.h(&x, &u, &mut hx)?;
            model.f_jacobian(&x, &u, &mut fj)?;
            model.h_jacobian(&x, &u, &mut hj)?;
        }
        Ok::<(), models::ModelError>(())
    });
    r.unwrap();
    assert_eq!(n, 0, "{n} allocations in 100 evaluations of f, h, F, H");
    assert!(fx[0] > 0.0 && hj[(0, 0)] == 1.0 && fj[(2, 2)] < 1.0);
}
