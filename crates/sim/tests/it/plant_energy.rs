//! Integrator accuracy: the free, frictionless Baxter arm (no spring, no environment,
//! zero torque) conserves its total energy `kinetic + potential` to a stated tolerance.

use crate::common;
use admittance_sim::{Integrator, Plant};
use common::*;

/// Runs `seconds` of free motion at `rate_hz` from the mid-range pose with an initial
/// velocity; returns the largest |E(t) - E(0)| divided by the largest kinetic energy
/// reached (the energy exchanged, a scale free of the potential's arbitrary zero).
fn relative_energy_error(integrator: Integrator, rate_hz: f64, seconds: f64) -> f64 {
    let model = baxter();
    let mut cfg = config(rate_hz, integrator);
    cfg.initial_q = mid_pose(&model);
    cfg.initial_qdot = vec![0.5, -0.3, 0.8, 0.4, -1.0, 0.6, 1.5];
    let mut plant = Plant::new(&model, &cfg).unwrap();
    let (ke0, pe0) = plant.energy();
    let e0 = ke0 + pe0;
    let mut max_dev: f64 = 0.0;
    let mut max_ke = ke0;
    let steps = (seconds * rate_hz).round() as usize;
    let zero = [0.0; 7];
    for _ in 0..steps {
        plant.step(&zero).unwrap();
        let (ke, pe) = plant.energy();
        max_dev = max_dev.max((ke + pe - e0).abs());
        max_ke = max_ke.max(ke);
    }
    assert!(plant.q().iter().all(|q| q.is_finite()));
    max_dev / max_ke
}

/// First order; in velocity form with a configuration-dependent mass matrix it is not
/// exactly symplectic, and the error grows slowly with time (measured 1.5e-2 here).
#[test]
fn semi_implicit_euler_conserves_energy_to_2_5e_2_over_2_s_at_5_khz() {
    let err = relative_energy_error(Integrator::SemiImplicitEuler, 5000.0, 2.0);
    eprintln!("semi_implicit_euler: max |dE| / max KE = {err:e}");
    assert!(err < 2.5e-2, "{err}");
}

/// Fourth order (measured 4e-11 here).
#[test]
fn rk4_split_conserves_energy_to_1e_9_over_2_s_at_5_khz() {
    let err = relative_energy_error(Integrator::Rk4Split, 5000.0, 2.0);
    eprintln!("rk4_split: max |dE| / max KE = {err:e}");
    assert!(err < 1e-9, "{err}");
}

/// The orders of accuracy show: halving the step halves the semi-implicit Euler error
/// (first order) and divides the RK4 error by about 16 (fourth order).
#[test]
fn energy_error_shrinks_with_the_step_at_each_scheme_s_order() {
    let e1 = relative_energy_error(Integrator::SemiImplicitEuler, 1000.0, 0.5);
    let e2 = relative_energy_error(Integrator::SemiImplicitEuler, 2000.0, 0.5);
    eprintln!(
        "semi_implicit_euler: 1 kHz {e1:e}, 2 kHz {e2:e}, ratio {}",
        e1 / e2
    );
    assert!(e1 / e2 > 1.6 && e1 / e2 < 2.5, "{e1} {e2}");
    let r1 = relative_energy_error(Integrator::Rk4Split, 500.0, 0.5);
    let r2 = relative_energy_error(Integrator::Rk4Split, 1000.0, 0.5);
    eprintln!("rk4_split: 500 Hz {r1:e}, 1 kHz {r2:e}, ratio {}", r1 / r2);
    assert!(r1 / r2 > 10.0, "{r1} {r2}");
}
