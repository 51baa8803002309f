//! The integration tests of this crate as one test binary (one link instead of one per
//! file: the test build is the longest part of a fresh clone's test command). Tests
//! that install a counting global allocator stay binaries of their own beside it.

#[path = "../common/mod.rs"]
mod common;

mod contact;
mod excitation_trajectory;
mod gains_and_health;
mod gates;
mod hand_contact;
mod learned_observers;
mod observer_scenarios;
mod panda;
mod scenarios;
