//! The counting allocator counts this thread's allocations and only those.

use admittance_testkit::{allocations, count_allocations, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn counts_allocations_reallocations_and_zeroed_allocations() {
    assert_eq!(
        count_allocations(|| drop(std::hint::black_box(vec![1u8; 16]))),
        1
    );
    assert_eq!(
        count_allocations(|| drop(std::hint::black_box(vec![0u64; 1024]))),
        1
    );
    let mut v: Vec<u8> = Vec::with_capacity(1);
    let grown = count_allocations(|| {
        for i in 0..100u8 {
            v.push(std::hint::black_box(i));
        }
    });
    assert!(grown >= 1, "growing a vector reallocates ({grown} counted)");
    let before = allocations();
    let boxed = Box::new(std::hint::black_box(7u32));
    assert_eq!(allocations() - before, 1);
    // Freeing is not an allocation.
    assert_eq!(count_allocations(|| drop(boxed)), 0);
    let mut x = 0.0f64;
    assert_eq!(
        count_allocations(|| {
            for k in 0..1000 {
                x += std::hint::black_box(k as f64).sqrt();
            }
        }),
        0
    );
    assert!(x > 0.0);
}

#[test]
fn other_threads_are_not_counted() {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    let started = Arc::new(AtomicBool::new(false));
    let stop = Arc::new(AtomicBool::new(false));
    let (started_flag, stop_flag) = (started.clone(), stop.clone());
    let noisy = std::thread::spawn(move || {
        let mut n = 0usize;
        loop {
            n += std::hint::black_box(vec![0u8; 64]).len();
            started_flag.store(true, Ordering::Release);
            if stop_flag.load(Ordering::Acquire) {
                return n;
            }
        }
    });
    while !started.load(Ordering::Acquire) {
        std::hint::spin_loop();
    }
    let mut acc = 0u64;
    let counted = count_allocations(|| {
        for k in 0..200_000u64 {
            acc = acc.wrapping_add(std::hint::black_box(k));
        }
    });
    stop.store(true, Ordering::Release);
    assert!(noisy.join().unwrap() > 0);
    assert_eq!(counted, 0, "allocations of another thread were counted");
    assert!(acc > 0);
}
