//! Learning layer of `admittance`: radial-basis-function networks.
//!
//! * [`rbf`]: the Gaussian RBF layer of the adaptive controller (docs/method.md sections 3-4):
//!   preallocated capacity, sigma-modified weight adaptation, node relevance tracking,
//!   discard and grow at run time without allocation.
//! * [`broad`]: the flat ("broad") RBF network of the force-sensorless observer
//!   (docs/method.md section 5): ridge regression on free-motion data, incremental growth.

#![warn(missing_docs)]

pub mod broad;
mod exp;
pub mod rbf;
