//! The integration tests of this crate as one test binary (one link instead of one per
//! file: the test build is the longest part of a fresh clone's test command). Tests
//! that install a counting global allocator stay binaries of their own beside it.

#[path = "../common.rs"]
mod common;

mod bad_input;
mod excitation;
mod identification;
mod mount;
mod oracle;
mod payload;
mod perturbed;
mod physical_files;
mod properties;
mod real_descriptions;
mod regressor;
mod spring_tails;
