//! The joint-torque regressor against Pinocchio's `computeJointTorqueRegressor` (fixtures in
//! tests/fixtures/regressor, made by scripts/oracle/generate_regressor_fixtures.py)
//! and against our own RNEA, and the base parameters' rank.

use crate::common;
use admittance_dynamics::*;
use nalgebra::DMatrix;
use serde::Deserialize;

#[derive(Deserialize)]
struct Case {
    q: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    regressor: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct Fixture {
    urdf: String,
    base: String,
    tip: String,
    parameters: Vec<f64>,
    cases: Vec<Case>,
}

fn rows(r: &[Vec<f64>]) -> DMatrix<f64> {
    DMatrix::from_fn(r.len(), r[0].len(), |i, j| r[i][j])
}

#[test]
fn regressor_equals_pinocchio_on_every_fixture_arm() {
    let dir = common::fixtures_dir().join("regressor");
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .expect("regressor fixtures exist")
        .map(|e| e.unwrap().path())
        .collect();
    paths.sort();
    assert!(paths.len() >= 33, "{} regressor fixtures", paths.len());
    let mut worst: f64 = 0.0;
    for path in &paths {
        let fx: Fixture = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let urdf = dir.join(&fx.urdf);
        let model = Model::from_urdf_file(&urdf, Some(&fx.base), Some(&fx.tip))
            .unwrap_or_else(|e| panic!("{e}"));
        let ours = inertial_parameters(&model);
        for (a, b) in ours.iter().zip(&fx.parameters) {
            assert!(
                (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                "{}: parameters {a} vs {b}",
                path.display()
            );
        }
        let mut data = Data::new(&model);
        for case in &fx.cases {
            let y = joint_torque_regressor(&model, &mut data, &case.q, &case.v, &case.a).unwrap();
            let expected = rows(&case.regressor);
            let err = (y - &expected).norm() / expected.norm().max(1e-12);
            worst = worst.max(err);
            assert!(err <= 1e-10, "{}: relative error {err:e}", path.display());
        }
    }
    eprintln!(
        "regressor vs Pinocchio: {} files, worst relative error {worst:e}",
        paths.len()
    );
}

#[test]
fn regressor_times_parameters_is_rnea() {
    for model in common::all_arms() {
        let n = model.nq();
        let mut data = Data::new(&model);
        let pi = nalgebra::DVector::from_vec(inertial_parameters(&model));
        for k in 0..5 {
            let s = |i: usize, c: f64| ((i * 7 + k * 3) as f64 * c).sin() * 1.3;
            let q: Vec<f64> = (0..n).map(|i| s(i, 0.7)).collect();
            let v: Vec<f64> = (0..n).map(|i| s(i, 1.1)).collect();
            let a: Vec<f64> = (0..n).map(|i| s(i, 1.9) * 3.0).collect();
            let tau = rnea(&model, &mut data, &q, &v, &a).unwrap().clone();
            let y = joint_torque_regressor(&model, &mut data, &q, &v, &a).unwrap();
            let err = (y * &pi - &tau).norm();
            assert!(
                err <= 1e-10 * (1.0 + tau.norm()),
                "{}: {err:e}",
                model.robot_name
            );
        }
    }
}

#[test]
fn parameters_round_trip_and_replace_the_bodies() {
    let model = common::baxter();
    let mut pi = inertial_parameters(&model);
    pi[0] *= 2.0; // body 0's mass
    let changed = with_inertial_parameters(&model, &pi).unwrap();
    assert_eq!(changed.bodies[0].mass, 2.0 * model.bodies[0].mass);
    assert_eq!(inertial_parameters(&changed), pi);
    assert!(with_inertial_parameters(&model, &pi[1..]).is_err());
}

#[test]
fn base_parameters_of_baxter() {
    let model = common::baxter();
    let base = BaseParameters::new(&model, 200, 7).unwrap();
    // A fixed-base serial chain of 7 revolute joints has far fewer identifiable
    // combinations than its 70 parameters; the first body contributes only I_zz about
    // its axis (and nothing else), so the rank is well below 70 and above 7.
    let r = base.rank();
    assert!(r > 7 && r < 70, "rank {r}");
    assert_eq!(base.independent().len(), r);
    // Every regressor column is the independent columns times beta: Y = Y_b [I beta] P^T.
    let mut data = Data::new(&model);
    let q = [0.3, -0.2, 0.5, 1.0, -0.4, 0.8, 0.2];
    let v = [0.5, -0.3, 0.2, 0.4, -0.6, 0.1, 0.9];
    let a = [1.0, 0.5, -0.5, 0.2, 0.3, -0.1, 0.7];
    let y = joint_torque_regressor(&model, &mut data, &q, &v, &a)
        .unwrap()
        .clone();
    let pi = nalgebra::DVector::from_vec(inertial_parameters(&model));
    let pb = base.base_values(pi.as_slice());
    let yb = DMatrix::from_fn(7, r, |i, j| y[(i, base.independent()[j])]);
    let err = (&yb * &pb - &y * &pi).norm();
    assert!(err <= 1e-8 * (1.0 + (&y * &pi).norm()), "{err:e}");
}
