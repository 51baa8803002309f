//! The payload fit: on torques RNEA computes for the arm with an extra body at the tip, it
//! recovers that body exactly; with noise it stays physically possible and close; and the
//! identification carrying it predicts the arm with the payload.

use crate::common;
use admittance_dynamics::spatial::rpy_to_matrix;
use admittance_dynamics::*;
use nalgebra::{Matrix3, Vector3};

fn motion(model: &Model, seconds: f64, seed: u64) -> Excitation {
    excitation(
        model,
        &ExcitationSettings {
            duration: seconds,
            period: seconds,
            rate_hz: 100.0,
            iterations: 100,
            seed,
            ..Default::default()
        },
    )
    .unwrap()
}

fn rnea_torques(model: &Model, e: &Excitation) -> Vec<f64> {
    let n = model.nq();
    let mut data = Data::new(model);
    let mut out = Vec::with_capacity(e.q.len());
    for k in 0..e.len() {
        let s = k * n..(k + 1) * n;
        let tau = rnea(
            model,
            &mut data,
            &e.q[s.clone()],
            &e.qdot[s.clone()],
            &e.qddot[s],
        )
        .unwrap();
        out.extend_from_slice(tau.as_slice());
    }
    out
}

fn tool() -> Payload {
    let r = rpy_to_matrix(0.3, -0.2, 0.5);
    Payload {
        mass: 1.7,
        com: Vector3::new(0.03, -0.05, 0.08),
        inertia: r * Matrix3::from_diagonal(&Vector3::new(0.010, 0.008, 0.004)) * r.transpose(),
    }
}

fn samples<'a>(e: &'a Excitation, tau: &'a [f64]) -> Samples<'a> {
    Samples {
        q: &e.q,
        qdot: &e.qdot,
        qddot: &e.qddot,
        tau,
        dof: e.dof,
    }
}

#[test]
fn a_body_at_the_tip_is_recovered_exactly_from_noiseless_torques() {
    let arm = common::baxter();
    // The tip frame is offset and turned from the last joint's frame: the fit must express
    // the payload in the tip frame.
    assert!(arm.tip().placement.translation.norm() > 0.0);
    let truth = tool();
    let with_tool = arm.with_payload(&truth).unwrap();
    let e = motion(&arm, 20.0, 4);
    let tau = rnea_torques(&with_tool, &e);
    let ident = Identification::from_model(arm.clone());
    let p = identify_payload(&ident, &samples(&e, &tau)).unwrap();
    eprintln!("recovered {p:?}");
    assert!(
        (p.mass - truth.mass).abs() < 1e-6 * truth.mass,
        "{} vs {}",
        p.mass,
        truth.mass
    );
    assert!(
        (p.com - truth.com).norm() < 1e-7,
        "{} vs {}",
        p.com,
        truth.com
    );
    assert!(
        (p.inertia - truth.inertia).norm() < 1e-6 * truth.inertia.norm(),
        "{} vs {}",
        p.inertia,
        truth.inertia
    );
    // The identification carrying it predicts the arm with the tool.
    let carried = ident.with_payload(&p).unwrap();
    let rms = carried.false_torque_rms(&samples(&e, &tau)).unwrap();
    assert!(rms.iter().all(|r| *r < 1e-6), "{rms:?}");
    assert!(ident
        .false_torque_rms(&samples(&e, &tau))
        .unwrap()
        .iter()
        .any(|r| *r > 0.1));
}

#[test]
fn with_noise_and_joint_terms_the_payload_stays_physical_and_close() {
    let arm = common::baxter();
    let truth = Payload::point_mass(0.8, Vector3::new(0.0, 0.0, 0.1));
    let with_tool = arm.with_payload(&truth).unwrap();
    let e = motion(&arm, 20.0, 5);
    let terms: Vec<JointTerms> = (0..7)
        .map(|i| JointTerms {
            armature: 0.05,
            viscous: 0.5 + 0.1 * i as f64,
            coulomb_width: 0.01,
            offset: 0.1,
            ..Default::default()
        })
        .collect();
    let mut tau = rnea_torques(&with_tool, &e);
    // Deterministic noise of 0.2 N m rms and the joint terms the identification knows.
    let mut state = 7u64;
    for (k, t) in tau.iter_mut().enumerate() {
        let (i, row) = (k % 7, k / 7);
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let u = (state >> 11) as f64 / (1u64 << 53) as f64;
        *t += 0.2 * 3f64.sqrt() * (2.0 * u - 1.0)
            + terms[i].torque(e.q[row * 7 + i], e.qdot[row * 7 + i], e.qddot[row * 7 + i]);
    }
    let mut ident = Identification::from_model(arm.clone());
    ident.joint_terms = terms;
    let p = identify_payload(&ident, &samples(&e, &tau)).unwrap();
    eprintln!("noisy: {p:?}");
    let body = Inertia::from_com(p.mass, p.com, p.inertia);
    assert!(is_physically_consistent(&body), "{p:?}");
    assert!(
        (p.mass - truth.mass).abs() < 0.05 * truth.mass,
        "{}",
        p.mass
    );
    assert!((p.com - truth.com).norm() < 0.01, "{}", p.com);
}

#[test]
fn a_payload_at_a_base_fixed_tip_or_too_few_samples_is_an_error() {
    let arm = common::baxter();
    let ident = Identification::from_model(arm.clone());
    let e = motion(&arm, 10.0, 1);
    let tau = rnea_torques(&arm, &e);
    let few = Samples {
        q: &e.q[..70],
        qdot: &e.qdot[..70],
        qddot: &e.qddot[..70],
        tau: &tau[..70],
        dof: 7,
    };
    let err = identify_payload(&ident, &few).unwrap_err().to_string();
    assert!(err.contains("at least"), "{err}");
    let wrong = Samples {
        dof: 6,
        ..samples(&e, &tau)
    };
    assert!(identify_payload(&ident, &wrong).is_err());
}
