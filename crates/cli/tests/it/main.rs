//! The integration tests of this crate as one test binary (one link instead of one per
//! file: the test build is the longest part of a fresh clone's test command). Tests
//! that install a counting global allocator stay binaries of their own beside it.

mod contact_cli;
mod deploy_cli;
mod dynamics_cli;
mod evaluate_settings;
mod excite_cli;
mod free_motion;
mod gains_health_cli;
mod identify_cli;
mod import_cli;
mod payload_cli;
mod planted_files;
mod real_spring_tangent;
mod reliability;
mod report_cli;
mod ros2_cli;
mod run_arm;
mod run_cli;
mod run_safety;
mod run_variants_interrupt;
mod train_cli;
mod train_safety;
mod train_validation;
