//! Test helpers shared by the workspace's test binaries (a dev-dependency only).
//!
//! # Counting allocator
//!
//! The real-time contract (STANDARDS: the control step, observer update and dynamics calls
//! allocate nothing after construction) is tested by wrapping the system allocator in
//! [`CountingAllocator`], which counts the allocations made by each thread. The count is
//! per thread because the test harness runs tests on several threads at once: a global
//! count would see the allocations of other tests and make the assertion flaky.
//!
//! A test binary installs it with one line and measures a closure with
//! [`count_allocations`]:
//!
//! ```
//! #[global_allocator]
//! static GLOBAL: admittance_testkit::CountingAllocator = admittance_testkit::CountingAllocator;
//!
//! fn main() {
//!     let mut state = vec![0.0; 7]; // construction may allocate
//!     let n = admittance_testkit::count_allocations(|| state.iter_mut().for_each(|x| *x += 1.0));
//!     assert_eq!(n, 0);
//!     let one = admittance_testkit::count_allocations(|| drop(std::hint::black_box(vec![0u8; 8])));
//!     assert_eq!(one, 1);
//! }
//! ```
//!
//! [`count_allocations`] panics if the counting allocator is not the binary's global
//! allocator, so a test cannot pass by counting nothing.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};

thread_local! {
    // `const` initialisation without a destructor: reading it never allocates and never
    // registers a destructor, so the allocator can use it re-entrantly.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// Set by the first allocation that goes through [`CountingAllocator`].
static INSTALLED: AtomicBool = AtomicBool::new(false);

/// A global allocator that forwards to [`System`] and counts, per thread, every call that
/// obtains memory (`alloc`, `alloc_zeroed`, `realloc`). Deallocations are not counted.
#[derive(Clone, Copy, Debug, Default)]
pub struct CountingAllocator;

impl CountingAllocator {
    #[inline]
    fn record(&self) {
        // `try_with`: during thread teardown the slot may be gone; such allocations are
        // not in any measured closure and are simply not counted.
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get().wrapping_add(1)));
        if !INSTALLED.load(Ordering::Relaxed) {
            INSTALLED.store(true, Ordering::Relaxed);
        }
    }
}

// SAFETY: every method forwards its arguments unchanged to `System`, which upholds the
// `GlobalAlloc` contract; the only extra work is a thread-local counter update and an
// atomic flag store, neither of which allocates, unwinds or touches the memory handed out.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        self.record();
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract (non-zero size
        // layout), which is exactly what `System.alloc` requires.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        self.record();
        // SAFETY: as for `alloc`; the contract of `alloc_zeroed` is the same.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by this allocator, i.e. by `System` (every
        // allocating method forwards to it), with this `layout`, as the caller guarantees.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        self.record();
        // SAFETY: `ptr` came from `System` with `layout` (see `dealloc`), and the caller
        // guarantees `new_size` is non-zero and does not overflow when rounded to the
        // alignment, as `System.realloc` requires.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Allocations made by the current thread since it started (wrapping), as seen by
/// [`CountingAllocator`]. Compare two readings, or use [`count_allocations`].
///
/// # Panics
/// If [`CountingAllocator`] is not the global allocator of this binary.
pub fn allocations() -> usize {
    assert_installed();
    ALLOCATIONS.with(Cell::get)
}

/// Runs `f` on the current thread and returns how many allocations it made (allocations
/// of other threads meanwhile are not counted).
///
/// # Panics
/// If [`CountingAllocator`] is not the global allocator of this binary (the count would
/// be zero whatever `f` does), or if `f` panics.
pub fn count_allocations(f: impl FnOnce()) -> usize {
    let before = allocations();
    f();
    allocations().wrapping_sub(before)
}

fn assert_installed() {
    // Any Rust program has allocated before a test runs (the harness builds its test
    // list), so an allocator that is installed has seen at least one call by now.
    assert!(
        INSTALLED.load(Ordering::Relaxed),
        "admittance_testkit::CountingAllocator is not the global allocator of this binary: \
         add `#[global_allocator] static GLOBAL: admittance_testkit::CountingAllocator = \
         admittance_testkit::CountingAllocator;` to the test file"
    );
}
