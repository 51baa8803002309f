//! The real-time contract: after `Model` and `Data` are built, no algorithm allocates.
//! A counting global allocator wraps the system one for this test binary.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use admittance_dynamics::*;
use nalgebra::Vector6;

struct Counting;

// Per thread: the test harness's own threads may allocate at any time; only the thread
// that runs the algorithms is counted.
thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn bump() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        bump();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        bump();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        bump();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn no_algorithm_allocates_after_construction() {
    let model = common::baxter();
    let mut data = Data::new(&model);
    let q = [0.1, -0.4, 0.3, 1.2, -0.2, 0.6, 0.1];
    let v = [0.5, -0.3, 0.2, 0.4, -0.6, 0.1, 0.9];
    let a = [1.0, 0.5, -0.5, 0.2, 0.3, -0.1, 0.7];
    let w = Vector6::new(1.0, 2.0, 3.0, 0.1, 0.2, 0.3);
    let short = [0.0; 3];
    let run = |data: &mut Data| {
        rnea(&model, data, &q, &v, &a).unwrap();
        rnea_with_tip_wrench(&model, data, &q, &v, &a, &w).unwrap();
        crba(&model, data, &q).unwrap();
        coriolis_matrix(&model, data, &q, &v).unwrap();
        momentum_observer_terms(&model, data, &q, &v).unwrap();
        gravity_torque(&model, data, &q).unwrap();
        nonlinear_effects(&model, data, &q, &v).unwrap();
        aba(&model, data, &q, &v, &a).unwrap();
        aba_with_tip_wrench(&model, data, &q, &v, &a, &w).unwrap();
        forward_kinematics(&model, data, &q).unwrap();
        tip_jacobian(&model, data, &q).unwrap();
        frame_jacobian(&model, data, &q, 3).unwrap();
        tip_jdot_qdot(&model, data, &q, &v).unwrap();
        kinetic_energy(&model, data, &q, &v).unwrap();
        potential_energy(&model, data, &q).unwrap();
        // Errors are reported without allocating too.
        assert!(rnea(&model, data, &short, &v, &a).is_err());
        assert!(frame_jacobian(&model, data, &q, 999).is_err());
    };
    run(&mut data); // warm-up
    let before = ALLOCATIONS.with(Cell::get);
    for _ in 0..100 {
        run(&mut data);
    }
    let after = ALLOCATIONS.with(Cell::get);
    assert_eq!(
        after - before,
        0,
        "{} allocations in 100 rounds of every algorithm",
        after - before
    );
    // The counter itself sees this thread's allocations.
    drop(std::hint::black_box(vec![1u8; 16]));
    assert!(ALLOCATIONS.with(Cell::get) > after);
}
