//! Without the counting allocator installed, counting refuses rather than reporting 0.

#[test]
#[should_panic(expected = "is not the global allocator")]
fn counting_without_the_allocator_panics() {
    let _ = admittance_testkit::count_allocations(|| drop(std::hint::black_box(vec![1u8; 4])));
}
