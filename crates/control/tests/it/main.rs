//! The integration tests of this crate as one test binary (one link instead of one per
//! file: the test build is the longest part of a fresh clone's test command). Tests
//! that install a counting global allocator stay binaries of their own beside it.

#[path = "../common/mod.rs"]
mod common;

mod admittance;
mod closed_loop;
mod contact;
mod joint_values;
mod neural_api;
mod safe_hold;
mod task_space;
