//! The integration tests of this crate as one test binary (one link instead of one per
//! file: the test build is the longest part of a fresh clone's test command). Tests
//! that install a counting global allocator stay binaries of their own beside it.

#[path = "../common/mod.rs"]
mod common;

mod config;
mod plant;
mod plant_energy;
mod sensors;
