//! Perturbed models: the simulator's true arm against the controller's nominal model.

use crate::common;
use admittance_dynamics::*;
use nalgebra::{DVector, Vector3};

const Q: [f64; 7] = [0.3, -0.7, 0.4, 1.3, -0.5, 0.9, 0.2];
const V: [f64; 7] = [0.4, -0.2, 0.3, 0.5, -0.6, 0.2, 0.8];
const A: [f64; 7] = [1.0, -0.5, 0.5, 0.2, 0.3, -0.1, 0.7];

#[test]
fn scaling_every_body_scales_every_torque() {
    let nominal = common::baxter();
    let heavy = nominal.with_scaled_inertias(1.2).unwrap();
    let (mut d0, mut d1) = (Data::new(&nominal), Data::new(&heavy));
    let t0 = rnea(&nominal, &mut d0, &Q, &V, &A).unwrap().clone();
    let t1 = rnea(&heavy, &mut d1, &Q, &V, &A).unwrap().clone();
    assert!((&t1 - &t0 * 1.2).norm() < 1e-10 * t0.norm());
    assert!((heavy.total_moving_mass() - 1.2 * nominal.total_moving_mass()).abs() < 1e-12);
    // Per-body scales: only the last body changes, so joints' torques change by its share.
    let mut scales = vec![1.0; 7];
    scales[6] = 2.0;
    let wrist = nominal.with_body_scales(&scales).unwrap();
    assert!((wrist.bodies[6].mass - 2.0 * nominal.bodies[6].mass).abs() < 1e-15);
    assert_eq!(wrist.bodies[5], nominal.bodies[5]);
    assert!(nominal.with_scaled_inertias(-1.0).is_err());
    assert!(nominal.with_scaled_inertias(f64::NAN).is_err());
    assert!(nominal.with_body_scales(&[1.0; 3]).is_err());
}

#[test]
fn a_point_payload_adds_its_weight_through_the_jacobian() {
    let nominal = common::baxter();
    let mass = 2.5;
    let loaded = nominal
        .with_payload(&Payload::point_mass(mass, Vector3::zeros()))
        .unwrap();
    let (mut d0, mut d1) = (Data::new(&nominal), Data::new(&loaded));
    let g0 = gravity_torque(&nominal, &mut d0, &Q).unwrap().clone();
    let g1 = gravity_torque(&loaded, &mut d1, &Q).unwrap().clone();
    let j = tip_jacobian(&nominal, &mut d0, &Q).unwrap().clone();
    // Holding the payload against gravity takes -J_v^T (m g) more torque.
    let weight = nominal.gravity * mass;
    let expected: DVector<f64> = -(j.fixed_rows::<3>(0).transpose() * weight);
    assert!(
        (&g1 - &g0 - &expected).norm() < 1e-10,
        "{} vs {}",
        &g1 - &g0,
        expected
    );
    assert!((loaded.total_moving_mass() - nominal.total_moving_mass() - mass).abs() < 1e-12);
    // A payload with its own inertia, offset from the tip, keeps M symmetric positive definite.
    let payload = Payload {
        mass: 1.0,
        com: Vector3::new(0.0, 0.0, 0.05),
        inertia: nalgebra::Matrix3::from_diagonal(&Vector3::new(2e-3, 2e-3, 1e-3)),
    };
    let tool = nominal.with_payload(&payload).unwrap();
    let mut d2 = Data::new(&tool);
    let m = crba(&tool, &mut d2, &Q).unwrap().clone();
    assert!(m.clone().symmetric_eigenvalues().min() > 0.0);
    assert!(nominal
        .with_payload(&Payload::point_mass(-1.0, Vector3::zeros()))
        .is_err());
}

/// `bias_and_gravity` is `mass_matrix_and_bias` without the matrix: the same bias and
/// gravity bits (the plant's held-mass-matrix steps rely on it), at poses and velocities
/// along a path, on the nominal and a perturbed arm.
#[test]
fn bias_and_gravity_equals_mass_matrix_and_bias_bit_for_bit() {
    let nominal = common::baxter();
    let heavy = nominal.with_scaled_inertias(1.3).unwrap();
    for model in [&nominal, &heavy] {
        let (mut d0, mut d1) = (Data::new(model), Data::new(model));
        for k in 0..40 {
            let q: Vec<f64> = (0..7).map(|j| Q[j] + 0.37 * (k * 7 + j) as f64).collect();
            let v: Vec<f64> = (0..7).map(|j| V[j] * (1.0 + 0.1 * k as f64)).collect();
            for gravity in [false, true] {
                mass_matrix_and_bias(model, &mut d0, &q, &v, gravity).unwrap();
                bias_and_gravity(model, &mut d1, &q, &v, gravity).unwrap();
                let bits = |x: &DVector<f64>| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&d0.nonlinear_effects), bits(&d1.nonlinear_effects));
                if gravity {
                    assert_eq!(bits(&d0.gravity_torque), bits(&d1.gravity_torque));
                }
            }
        }
    }
    let mut data = Data::new(&nominal);
    assert!(bias_and_gravity(&nominal, &mut data, &Q[..3], &V, true).is_err());
}
