//! Python bindings of `admittance` (issue 15, part 1): the package `admittance`, built by
//! maturin from this crate (`pip install ./crates/python`). Thin: every function converts
//! its arguments, calls the Rust crates and converts the result; nothing is computed here
//! that the Rust API does not compute (docs/python.md).
//!
//! * [`model`]: `Model` and the dynamics functions;
//! * [`control`]: the controllers; [`observers`]: the external-torque observers and the
//!   observers' input filter; [`admittance`]: the admittance model;
//! * [`network`]: training, growing, saving and loading the observer's network;
//! * [`run`]: a scenario run, as `admittance run`; [`closed_loop`]: the Rust `ClosedLoop`,
//!   and the metrics and run folder of a loop stepped against a plant outside Rust;
//! * [`config`]: configuration dicts with the scenario files' keys; [`convert`]: arrays
//!   and errors.

#![warn(missing_docs)]

mod admittance;
mod bag;
mod closed_loop;
mod config;
mod contact;
mod control;
mod convert;
mod cosim;
mod cosim_free_motion;
mod free_motion;
mod identification;
mod identify_payload;
mod model;
mod network;
mod observers;
mod payload;
mod robot_loop;
mod run;

use pyo3::prelude::*;

/// The native module `admittance._admittance`; the package `admittance` re-exports it.
#[pymodule]
fn _admittance(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The defaults every front end shares (declared once, in the learning crate).
    m.add("DEFAULT_NODES", admittance_learning::broad::DEFAULT_NODES)?;
    m.add(
        "DEFAULT_SIGNAL_CUTOFF_HZ",
        admittance_loop::DEFAULT_SIGNAL_CUTOFF_HZ,
    )?;
    m.add(
        "COULOMB_WIDTH_CANDIDATES",
        admittance_dynamics::COULOMB_WIDTH_CANDIDATES.to_vec(),
    )?;
    m.add(
        "FIT_ACCELERATION_HZ",
        admittance_dynamics::FIT_ACCELERATION_HZ,
    )?;
    m.add(
        "TRAINING_RANGE_MARGIN",
        admittance_dynamics::TRAINING_RANGE_MARGIN,
    )?;
    m.add(
        "TRAINING_SPEED_MARGIN",
        admittance_dynamics::TRAINING_SPEED_MARGIN,
    )?;
    m.add_class::<model::PyModel>()?;
    for f in [
        wrap_pyfunction!(model::rnea, m)?,
        wrap_pyfunction!(model::crba, m)?,
        wrap_pyfunction!(model::gravity, m)?,
        wrap_pyfunction!(model::coriolis, m)?,
        wrap_pyfunction!(model::tip_pose, m)?,
        wrap_pyfunction!(model::tip_jacobian, m)?,
        wrap_pyfunction!(model::aba, m)?,
        wrap_pyfunction!(network::train, m)?,
        wrap_pyfunction!(network::load_network, m)?,
        wrap_pyfunction!(run::run, m)?,
        wrap_pyfunction!(identification::identify, m)?,
        wrap_pyfunction!(identification::load_identification, m)?,
        wrap_pyfunction!(identification::excitation, m)?,
        wrap_pyfunction!(identify_payload::identify_payload, m)?,
        wrap_pyfunction!(bag::import_bag, m)?,
        wrap_pyfunction!(closed_loop::write_run_folder, m)?,
        wrap_pyfunction!(closed_loop::check_out_dir, m)?,
        wrap_pyfunction!(contact::calibrate_contact, m)?,
        wrap_pyfunction!(contact::load_contact_floor, m)?,
    ] {
        m.add_function(f)?;
    }
    m.add_class::<control::PyController>()?;
    m.add_class::<control::PyNeuralController>()?;
    m.add_class::<control::PyPdController>()?;
    m.add_class::<control::PyComputedTorqueController>()?;
    m.add_class::<observers::PyObserver>()?;
    m.add_class::<observers::PyMomentumObserver>()?;
    m.add_class::<observers::PyLearnedObserver>()?;
    m.add_class::<observers::PyHybridObserver>()?;
    m.add_class::<observers::PyOracleObserver>()?;
    m.add_class::<observers::PyInputConditioner>()?;
    m.add_class::<observers::PyEstimateLowPass>()?;
    m.add_class::<admittance::PyAdmittance>()?;
    m.add_class::<robot_loop::PyRobotLoop>()?;
    m.add_class::<contact::PyContactFloor>()?;
    m.add_class::<contact::PyContactDetector>()?;
    m.add_class::<closed_loop::PyClosedLoop>()?;
    m.add_class::<closed_loop::PyVariantRecorder>()?;
    m.add_class::<cosim::PyCosimStepper>()?;
    m.add_class::<cosim_free_motion::PyFreeMotionStepper>()?;
    m.add_class::<network::PyNetwork>()?;
    m.add_class::<identification::PyIdentification>()?;
    m.add_class::<payload::PyPayload>()?;
    m.add("RunFailed", m.py().get_type::<run::RunFailed>())?;
    Ok(())
}
