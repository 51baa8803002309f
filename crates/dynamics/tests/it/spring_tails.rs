//! Springs fitted over less than half a turn continue along their tangent beyond the
//! training motion's range (`JointTerms::spring_range`): an arm with a torsion spring
//! (linear in the angle, which the Fourier series only approximates) scored where its
//! shoulder goes beyond the range it was identified on.

use crate::identification::{motion, torques};
use admittance_dynamics::*;

/// The false torque (rms, N m) of `ident` on the motion `(q, qd, qdd)` whose torque is `tau`.
fn false_torque(ident: &Identification, q: &[f64], qd: &[f64], qdd: &[f64], tau: &[f64]) -> f64 {
    let n = ident.model.nq();
    let mut data = Data::new(&ident.model);
    let mut out = vec![0.0; n];
    let mut sq = 0.0;
    for (k, t) in tau.chunks_exact(n).enumerate() {
        let r = k * n..(k + 1) * n;
        ident
            .predict(&mut data, &q[r.clone()], &qd[r.clone()], &qdd[r], &mut out)
            .unwrap();
        sq += out.iter().zip(t).map(|(p, t)| (p - t).powi(2)).sum::<f64>();
    }
    (sq / tau.len() as f64).sqrt()
}

#[test]
fn a_spring_continues_along_its_tangent_beyond_the_training_range() {
    let urdf = crate::common::baxter();
    let n = urdf.nq();
    let shoulder = 1;
    // A torsion spring on the shoulder: 25 N m/rad about -0.55 rad (its range's middle).
    let spring = |q: f64| 25.0 * (q + 0.55);
    let terms: Vec<JointTerms> = (0..n)
        .map(|_| JointTerms {
            viscous: 0.5,
            coulomb: [0.8, 0.2],
            coulomb_width: 0.01,
            ..Default::default()
        })
        .collect();
    let with_spring = |q: &[f64], tau: &mut [f64]| {
        for (k, t) in tau.chunks_exact_mut(n).enumerate() {
            t[shoulder] += spring(q[k * n + shoulder]);
        }
    };
    let (q, qd, qdd) = motion(&urdf, 0.3, 30.0);
    let mut tau = torques(&urdf, &terms, &q, &qd, &qdd);
    with_spring(&q, &mut tau);
    let train = Samples {
        q: &q,
        qdot: &qd,
        qddot: &qdd,
        tau: &tau,
        dof: n,
    };
    let ident = identify(&urdf, &train, None, &IdentificationSettings::default()).unwrap();
    assert!(
        ident.summary.springs[shoulder],
        "{:?}",
        ident.summary.springs
    );
    let range = ident.summary.training_range[shoulder];
    assert_eq!(ident.joint_terms[shoulder].spring_range, Some(range));
    // Each joint's highest training speed is recorded beside its range.
    for (i, &top) in ident.summary.training_speed.iter().enumerate() {
        let highest = qd
            .iter()
            .skip(i)
            .step_by(n)
            .fold(0.0_f64, |m, v| m.max(v.abs()));
        assert_eq!(top, highest, "joint {i}");
    }
    assert_eq!(ident.summary.training_speed.len(), n);
    // Other motion, the shoulder 0.6 rad lower: up to 0.6 rad below its training range.
    let (mut q2, qd2, qdd2) = motion(&urdf, 1.7, 20.0);
    q2.iter_mut()
        .skip(shoulder)
        .step_by(n)
        .for_each(|x| *x -= 0.6);
    let lowest = q2
        .iter()
        .skip(shoulder)
        .step_by(n)
        .fold(f64::INFINITY, |a, &b| a.min(b));
    assert!(lowest < range[0] - 0.4, "{lowest} against {range:?}");
    let mut tau2 = torques(&urdf, &terms, &q2, &qd2, &qdd2);
    with_spring(&q2, &mut tau2);
    let tangent = false_torque(&ident, &q2, &qd2, &qdd2, &tau2);
    let mut series = ident.clone();
    series.joint_terms[shoulder].spring_range = None;
    let bent = false_torque(&series, &q2, &qd2, &qdd2, &tau2);
    eprintln!("false torque beyond the range: tangent {tangent:.3}, series {bent:.3} N m");
    assert!(
        tangent < 0.5 * bent,
        "tangent {tangent} against series {bent}"
    );
}
