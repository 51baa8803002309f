//! The integration tests of this crate as one test binary (one link instead of one per
//! file: the test build is the longest part of a fresh clone's test command). Tests
//! that install a counting global allocator stay binaries of their own beside it.

#[path = "../broad_common/mod.rs"]
mod broad_common;

mod broad_cv;
mod broad_destination;
mod broad_growth;
mod broad_identity;
mod broad_io;
mod broad_limits;
mod broad_refusals;
mod rbf_layer;
mod rbf_props;
