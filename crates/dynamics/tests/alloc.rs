//! The real-time contract: after `Model` and `Data` are built, no algorithm allocates.
//! The counting allocator of `admittance-testkit` wraps the system one for this test binary.

mod common;

use admittance_dynamics::*;
use admittance_testkit::count_allocations;
use nalgebra::Vector6;

#[global_allocator]
static GLOBAL: admittance_testkit::CountingAllocator = admittance_testkit::CountingAllocator;

#[test]
fn no_algorithm_allocates_after_construction() {
    let model = common::baxter();
    let mut data = Data::new(&model);
    let q = [0.1, -0.4, 0.3, 1.2, -0.2, 0.6, 0.1];
    let v = [0.5, -0.3, 0.2, 0.4, -0.6, 0.1, 0.9];
    let a = [1.0, 0.5, -0.5, 0.2, 0.3, -0.1, 0.7];
    let w = Vector6::new(1.0, 2.0, 3.0, 0.1, 0.2, 0.3);
    let short = [0.0; 3];
    let run = |data: &mut Data| {
        rnea(&model, data, &q, &v, &a).unwrap();
        rnea_with_tip_wrench(&model, data, &q, &v, &a, &w).unwrap();
        crba(&model, data, &q).unwrap();
        coriolis_matrix(&model, data, &q, &v).unwrap();
        momentum_observer_terms(&model, data, &q, &v).unwrap();
        gravity_torque(&model, data, &q).unwrap();
        nonlinear_effects(&model, data, &q, &v).unwrap();
        mass_matrix_and_bias(&model, data, &q, &v, true).unwrap();
        bias_and_gravity(&model, data, &q, &v, true).unwrap();
        aba(&model, data, &q, &v, &a).unwrap();
        aba_with_tip_wrench(&model, data, &q, &v, &a, &w).unwrap();
        forward_kinematics(&model, data, &q).unwrap();
        tip_jacobian(&model, data, &q).unwrap();
        frame_jacobian(&model, data, &q, 3).unwrap();
        tip_jdot_qdot(&model, data, &q, &v).unwrap();
        kinetic_energy(&model, data, &q, &v).unwrap();
        potential_energy(&model, data, &q).unwrap();
        joint_torque_regressor(&model, data, &q, &v, &a).unwrap();
        // Errors are reported without allocating too.
        assert!(rnea(&model, data, &short, &v, &a).is_err());
        assert!(frame_jacobian(&model, data, &q, 999).is_err());
    };
    run(&mut data); // warm-up
    let count = count_allocations(|| {
        for _ in 0..100 {
            run(&mut data);
        }
    });
    assert_eq!(
        count, 0,
        "{count} allocations in 100 rounds of every algorithm"
    );
    // The counter itself sees this thread's allocations.
    assert!(count_allocations(|| drop(std::hint::black_box(vec![1u8; 16]))) > 0);
}

#[test]
fn identified_prediction_and_joint_terms_do_not_allocate() {
    let model = common::baxter();
    let ident = Identification::from_model(model.clone());
    let mut data = Data::new(&model);
    let q = [0.1, -0.4, 0.3, 1.2, -0.2, 0.6, 0.1];
    let v = [0.5, -0.3, 0.2, 0.4, -0.6, 0.1, 0.9];
    let mut out = [0.0; 7];
    ident.predict(&mut data, &q, &v, &v, &mut out).unwrap();
    // A gain below 1 with the training's acceleration power: the gain follows the motion.
    let mut summary = ident.summary.clone();
    summary.acceleration_gain = 0.3;
    summary.acceleration_power = vec![0.01; 7];
    summary.settings.sample_rate_hz = Some(1000.0);
    let mut gains = AccelerationGains::new(&summary, None);
    let mut g = [0.0; 7];
    let count = count_allocations(|| {
        for _ in 0..100 {
            ident.predict(&mut data, &q, &v, &v, &mut out).unwrap();
            ident.joint_friction_torque(&q, &v, &mut out).unwrap();
            gains.update(&v, &mut g);
            ident
                .predict_with_gains(&mut data, &q, &v, &v, &g, &mut out)
                .unwrap();
        }
    });
    assert_eq!(count, 0);
    // The joints accelerating far above the noise rose within the 0.1 s; none fell below.
    assert!(g.iter().all(|&x| x >= 0.3) && g[6] > 0.3, "{g:?}");
}
