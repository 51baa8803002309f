//! Property tests of the dynamics algorithms on Baxter and on every fixture arm:
//! identities that hold for any correct rigid-body dynamics, checked on random states.

use crate::common;
use std::sync::OnceLock;

use admittance_dynamics::*;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use proptest::prelude::*;

fn arms() -> &'static [Model] {
    static ARMS: OnceLock<Vec<Model>> = OnceLock::new();
    ARMS.get_or_init(common::all_arms)
}

/// A random state for arm `index`: q within limits (or [-pi, pi]), v, a, tau.
fn state() -> impl Strategy<Value = (usize, Vec<f64>, Vec<f64>, Vec<f64>)> {
    let count = arms().len();
    (
        0..count,
        prop::collection::vec(0.0f64..1.0, 9),
        prop::collection::vec(-2.0f64..2.0, 9),
        prop::collection::vec(-5.0f64..5.0, 9),
    )
        .prop_map(|(i, u, v, a)| {
            let model = &arms()[i];
            let n = model.nq();
            let q = model
                .joints
                .iter()
                .zip(&u)
                .map(|(j, u)| {
                    let (lo, hi) = if j.limits.lower.is_finite() {
                        (j.limits.lower, j.limits.upper)
                    } else {
                        (-std::f64::consts::PI, std::f64::consts::PI)
                    };
                    lo + u * (hi - lo)
                })
                .collect();
            (i, q, v[..n].to_vec(), a[..n].to_vec())
        })
}

fn rel_err(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).norm() / (1.0 + b.norm())
}

fn advance(q: &[f64], v: &[f64], h: f64) -> Vec<f64> {
    q.iter().zip(v).map(|(q, v)| q + h * v).collect()
}

/// Rotation vector of a small rotation `r`: the axial part of `(R - R^T) / 2`, accurate
/// to third order (an acos-based logarithm loses half the digits near the identity).
fn log_so3(r: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ) * 0.5
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn mass_matrix_is_symmetric_positive_definite((i, q, _v, _a) in state()) {
        let model = &arms()[i];
        let mut data = Data::new(model);
        let m = crba(model, &mut data, &q).unwrap().clone();
        prop_assert!(rel_err(&m, &m.transpose()) < 1e-14);
        let eig = m.clone().symmetric_eigenvalues();
        prop_assert!(eig.min() > 0.0, "eigenvalues {eig}");
    }

    #[test]
    fn mass_matrix_agrees_with_rnea_columns((i, q, _v, _a) in state()) {
        let model = &arms()[i];
        let n = model.nq();
        let mut data = Data::new(model);
        let m = crba(model, &mut data, &q).unwrap().clone();
        let g = gravity_torque(model, &mut data, &q).unwrap().clone();
        for k in 0..n {
            let mut e = vec![0.0; n];
            e[k] = 1.0;
            let col = rnea(model, &mut data, &q, &vec![0.0; n], &e).unwrap() - &g;
            prop_assert!((col - m.column(k)).norm() < 1e-10 * (1.0 + m.norm()));
        }
    }

    #[test]
    fn rnea_inverts_aba((i, q, v, tau) in state()) {
        let model = &arms()[i];
        let mut data = Data::new(model);
        let qdd = aba(model, &mut data, &q, &v, &tau).unwrap().clone();
        let back = rnea(model, &mut data, &q, &v, qdd.as_slice()).unwrap();
        let tau = DVector::from_vec(tau);
        prop_assert!((back - &tau).norm() < 1e-9 * (1.0 + tau.norm()), "{back} vs {tau}");
    }

    #[test]
    fn coriolis_reproduces_nonlinear_effects_and_mdot_minus_2c_is_skew((i, q, v, _a) in state()) {
        let model = &arms()[i];
        let mut data = Data::new(model);
        let c = coriolis_matrix(model, &mut data, &q, &v).unwrap().clone();
        let g = gravity_torque(model, &mut data, &q).unwrap().clone();
        let h = nonlinear_effects(model, &mut data, &q, &v).unwrap().clone();
        let vv = DVector::from_column_slice(&v);
        prop_assert!((&c * &vv + &g - &h).norm() < 1e-10 * (1.0 + h.norm()));
        // Mdot along q(t) = q + t v by central differences.
        let step = 1e-6;
        let mp = crba(model, &mut data, &advance(&q, &v, step)).unwrap().clone();
        let mm = crba(model, &mut data, &advance(&q, &v, -step)).unwrap().clone();
        let mdot = (mp - mm) / (2.0 * step);
        let n_mat = &mdot - &c * 2.0;
        let skew_defect = (&n_mat + n_mat.transpose()).norm();
        prop_assert!(skew_defect < 1e-6 * (1.0 + mdot.norm()), "defect {skew_defect}");
        // And Mdot = C + C^T (the Christoffel form).
        prop_assert!((&mdot - (&c + c.transpose())).norm() < 1e-6 * (1.0 + mdot.norm()));
    }

    #[test]
    fn jacobian_matches_finite_differenced_kinematics((i, q, v, _a) in state()) {
        let model = &arms()[i];
        let mut data = Data::new(model);
        let j = tip_jacobian(model, &mut data, &q).unwrap().clone();
        let twist = &j * DVector::from_column_slice(&v);
        let step = 1e-6;
        forward_kinematics(model, &mut data, &advance(&q, &v, step)).unwrap();
        let plus = *data.tip_placement(model);
        forward_kinematics(model, &mut data, &advance(&q, &v, -step)).unwrap();
        let minus = *data.tip_placement(model);
        let lin = (plus.translation - minus.translation) / (2.0 * step);
        let ang = log_so3(&(plus.rotation * minus.rotation.transpose())) / (2.0 * step);
        let scale = 1.0 + twist.norm();
        prop_assert!((lin - twist.fixed_rows::<3>(0)).norm() < 1e-6 * scale);
        prop_assert!((ang - twist.fixed_rows::<3>(3)).norm() < 1e-6 * scale);
    }

    #[test]
    fn jdot_qdot_matches_finite_differences((i, q, v, _a) in state()) {
        let model = &arms()[i];
        let mut data = Data::new(model);
        let vv = DVector::from_column_slice(&v);
        let jdqd = *tip_jdot_qdot(model, &mut data, &q, &v).unwrap();
        let step = 1e-6;
        let jp = tip_jacobian(model, &mut data, &advance(&q, &v, step)).unwrap() * &vv;
        let jm = tip_jacobian(model, &mut data, &advance(&q, &v, -step)).unwrap() * &vv;
        let fd = (jp - jm) / (2.0 * step);
        prop_assert!((fd - jdqd).norm() < 1e-5 * (1.0 + jdqd.norm()), "{fd} vs {jdqd}");
    }

    #[test]
    fn tip_wrench_enters_as_jacobian_transpose((i, q, v, a) in state()) {
        let model = &arms()[i];
        let mut data = Data::new(model);
        let w = nalgebra::Vector6::new(3.0, -2.0, 5.0, 0.4, -0.3, 0.2);
        let tau = rnea(model, &mut data, &q, &v, &a).unwrap().clone();
        let with = rnea_with_tip_wrench(model, &mut data, &q, &v, &a, &w).unwrap().clone();
        let j = tip_jacobian(model, &mut data, &q).unwrap().clone();
        prop_assert!((&tau - j.transpose() * w - &with).norm() < 1e-10 * (1.0 + tau.norm()));
        // ABA with the same wrench inverts it.
        let qdd = aba_with_tip_wrench(model, &mut data, &q, &v, with.as_slice(), &w).unwrap();
        prop_assert!((qdd - DVector::from_column_slice(&a)).norm() < 1e-8 * (1.0 + with.norm()));
    }
}

/// Free, frictionless motion integrated with ABA (classical RK4, 0.1 ms) conserves total
/// energy: over 1 s the drift stays below 1e-6 of the energy scale for every arm (at
/// 0.5 ms the fastest fixture arm drifts 4e-5: RK4 truncation, shrinking as dt^4).
#[test]
fn free_motion_conserves_energy() {
    for model in arms() {
        let n = model.nq();
        let mut data = Data::new(model);
        let mut q: Vec<f64> = (0..n).map(|k| 0.3 * ((k as f64) * 1.7).sin()).collect();
        let mut v: Vec<f64> = (0..n).map(|k| 0.8 * ((k as f64) * 0.9).cos()).collect();
        let tau = vec![0.0; n];
        let energy = |data: &mut Data, q: &[f64], v: &[f64]| {
            kinetic_energy(model, data, q, v).unwrap() + potential_energy(model, data, q).unwrap()
        };
        let e0 = energy(&mut data, &q, &v);
        let scale = kinetic_energy(model, &mut data, &q, &v).unwrap()
            + model.total_moving_mass() * 9.81 * 0.5;
        let dt = 1e-4;
        let mut worst: f64 = 0.0;
        for _ in 0..10000 {
            let mut deriv = |q: &[f64], v: &[f64]| -> (Vec<f64>, Vec<f64>) {
                let a = aba(model, &mut data, q, v, &tau)
                    .unwrap()
                    .as_slice()
                    .to_vec();
                (v.to_vec(), a)
            };
            let (k1q, k1v) = deriv(&q, &v);
            let q2: Vec<f64> = (0..n).map(|k| q[k] + 0.5 * dt * k1q[k]).collect();
            let v2: Vec<f64> = (0..n).map(|k| v[k] + 0.5 * dt * k1v[k]).collect();
            let (k2q, k2v) = deriv(&q2, &v2);
            let q3: Vec<f64> = (0..n).map(|k| q[k] + 0.5 * dt * k2q[k]).collect();
            let v3: Vec<f64> = (0..n).map(|k| v[k] + 0.5 * dt * k2v[k]).collect();
            let (k3q, k3v) = deriv(&q3, &v3);
            let q4: Vec<f64> = (0..n).map(|k| q[k] + dt * k3q[k]).collect();
            let v4: Vec<f64> = (0..n).map(|k| v[k] + dt * k3v[k]).collect();
            let (k4q, k4v) = deriv(&q4, &v4);
            for k in 0..n {
                q[k] += dt / 6.0 * (k1q[k] + 2.0 * k2q[k] + 2.0 * k3q[k] + k4q[k]);
                v[k] += dt / 6.0 * (k1v[k] + 2.0 * k2v[k] + 2.0 * k3v[k] + k4v[k]);
            }
            worst = worst.max((energy(&mut data, &q, &v) - e0).abs());
        }
        assert!(
            worst < 1e-6 * scale,
            "{}: energy drift {worst} J (scale {scale} J)",
            model.source
        );
    }
}
