//! Identification recovers an arm it could describe, judged on motion it never saw, keeps
//! bodies physically possible, and its files round-trip and refuse damage.

use crate::common;
use std::collections::BTreeMap;

use admittance_dynamics::*;

/// A multi-sine motion (each joint its own frequencies, from `seed`) inside +-0.8 rad of
/// the middle of the joint's range, sampled at 200 Hz for `seconds`.
pub(crate) fn motion(model: &Model, seed: f64, seconds: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = model.nq();
    let steps = (seconds * 200.0) as usize;
    let (mut q, mut qd, mut qdd) = (vec![], vec![], vec![]);
    for k in 0..steps {
        let t = k as f64 / 200.0;
        for (i, j) in model.joints.iter().enumerate() {
            let mid = if j.limits.lower.is_finite() {
                0.5 * (j.limits.lower + j.limits.upper)
            } else {
                0.0
            };
            let (mut p, mut v, mut a) = (mid, 0.0, 0.0);
            for h in 1..=3 {
                let w = 2.0
                    * std::f64::consts::PI
                    * (0.1 + 0.13 * h as f64 + 0.017 * i as f64)
                    * (1.0 + 0.3 * seed);
                let amp = 0.8 / (3.0 * h as f64).sqrt() / 1.2;
                let ph = seed * (i + 2 * h) as f64;
                p += amp * (w * t + ph).sin();
                v += amp * w * (w * t + ph).cos();
                a -= amp * w * w * (w * t + ph).sin();
            }
            q.push(p);
            qd.push(v);
            qdd.push(a);
        }
    }
    let _ = n;
    (q, qd, qdd)
}

/// The Baxter the identification tests record: the URDF's arm with heavier and lighter links
/// than the URDF says.
pub(crate) fn heavier_baxter(urdf: &Model) -> Model {
    urdf.with_body_scales(&[1.3, 0.8, 1.2, 1.1, 0.9, 1.25, 1.1])
        .unwrap()
}

fn truth_terms(n: usize) -> Vec<JointTerms> {
    (0..n)
        .map(|i| JointTerms {
            armature: 0.05 + 0.01 * i as f64,
            viscous: 1.0 + 0.2 * i as f64,
            coulomb: [2.0 - 0.1 * i as f64, 0.5],
            coulomb_width: 0.01,
            offset: 0.3 * (i as f64 - 3.0),
            spring: if i == 1 {
                [0.0, 8.0, 0.0, -2.0]
            } else {
                [0.0; 4]
            },
            spring_range: None,
        })
        .collect()
}

pub(crate) fn torques(
    model: &Model,
    terms: &[JointTerms],
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Vec<f64> {
    let n = model.nq();
    let mut data = Data::new(model);
    let mut out = Vec::with_capacity(q.len());
    for k in 0..q.len() / n {
        let r = k * n..(k + 1) * n;
        let tau = rnea(
            model,
            &mut data,
            &q[r.clone()],
            &qd[r.clone()],
            &qdd[r.clone()],
        )
        .unwrap();
        for i in 0..n {
            out.push(tau[i] + terms[i].torque(q[k * n + i], qd[k * n + i], qdd[k * n + i]));
        }
    }
    out
}

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

#[test]
fn recovers_an_arm_on_motion_it_never_saw() {
    let urdf = common::baxter();
    // The truth: heavier links than the URDF says, and friction, springs, rotor inertia.
    let truth = heavier_baxter(&urdf);
    let terms = truth_terms(7);
    let (q, qd, qdd) = motion(&urdf, 0.3, 30.0);
    let tau = torques(&truth, &terms, &q, &qd, &qdd);
    let train = Samples {
        q: &q,
        qdot: &qd,
        qddot: &qdd,
        tau: &tau,
        dof: 7,
    };
    let ident = identify(&urdf, &train, None, &IdentificationSettings::default()).unwrap();
    // Other motion: other frequencies and phases.
    let (q2, qd2, qdd2) = motion(&urdf, 1.7, 20.0);
    let tau2 = torques(&truth, &terms, &q2, &qd2, &qdd2);
    let mut data = Data::new(&ident.model);
    let mut pred = Vec::new();
    let mut out = [0.0; 7];
    for k in 0..q2.len() / 7 {
        let r = k * 7..(k + 1) * 7;
        ident
            .predict(
                &mut data,
                &q2[r.clone()],
                &qd2[r.clone()],
                &qdd2[r.clone()],
                &mut out,
            )
            .unwrap();
        pred.extend_from_slice(&out);
    }
    let urdf_pred = torques(
        &urdf,
        &vec![
            JointTerms {
                coulomb_width: 0.01,
                ..Default::default()
            };
            7
        ],
        &q2,
        &qd2,
        &qdd2,
    );
    let (ours, prior) = (rms(&pred, &tau2), rms(&urdf_pred, &tau2));
    eprintln!(
        "new motion rms: identified {ours:.4} N m, URDF {prior:.3} N m; {:?}",
        ident.summary
    );
    assert!(ours < 0.02 * prior, "identified {ours} vs URDF {prior}");
    assert!(
        ident.summary.springs[1],
        "joint 1's spring was found: {:?}",
        ident.summary.springs
    );
    for (b, body) in ident.model.bodies.iter().enumerate() {
        assert!(is_physically_consistent(body), "body {b}: {body:?}");
    }
    assert!(
        ident
            .summary
            .expected_false_torque_rms
            .iter()
            .all(|e| *e < 0.1),
        "{:?}",
        ident.summary.expected_false_torque_rms
    );
    assert!(ident.summary.base_parameters > 7 && ident.summary.base_parameters < 70);
}

/// Left unset, the Coulomb width is chosen on held-out motion among the candidates: an arm
/// whose friction has one of them gets it on every joint; given, the width is kept.
#[test]
fn the_coulomb_width_is_chosen_unless_given() {
    let urdf = common::baxter();
    let (q, qd, qdd) = motion(&urdf, 0.3, 30.0);
    for truth_width in [0.003, 0.005] {
        let terms: Vec<JointTerms> = truth_terms(7)
            .into_iter()
            .map(|t| JointTerms {
                coulomb_width: truth_width,
                ..t
            })
            .collect();
        let tau = torques(&urdf, &terms, &q, &qd, &qdd);
        let recording = [q.clone(), qd.clone(), qdd.clone(), tau];
        let train = samples(&recording);
        assert!(COULOMB_WIDTH_CANDIDATES.contains(&truth_width));
        let chosen = identify(&urdf, &train, None, &IdentificationSettings::default()).unwrap();
        let widths: Vec<f64> = chosen.joint_terms.iter().map(|t| t.coulomb_width).collect();
        assert_eq!(widths, vec![truth_width; 7], "truth {truth_width}");
        assert_eq!(chosen.summary.settings.coulomb_width, None);
        let given = IdentificationSettings {
            coulomb_width: Some(0.01),
            ..Default::default()
        };
        let kept = identify(&urdf, &train, None, &given).unwrap();
        assert!(kept.joint_terms.iter().all(|t| t.coulomb_width == 0.01));
        let total = |e: &[f64]| e.iter().map(|x| x * x).sum::<f64>();
        assert!(
            total(&chosen.summary.expected_false_torque_rms)
                < total(&kept.summary.expected_false_torque_rms),
            "the truth's width fits held-out motion better than 0.01"
        );
    }
}

/// The multi-sine motion of seed 0.9 for `seconds` and its torques with deterministic
/// pseudo-noise, uniform on +-`amplitude` (N m; `frequency` picks the sequence).
fn noisy_recording(model: &Model, seconds: f64, frequency: f64, amplitude: f64) -> [Vec<f64>; 4] {
    let (q, qd, qdd) = motion(model, 0.9, seconds);
    let mut tau = torques(model, &truth_terms(model.nq()), &q, &qd, &qdd);
    for (k, t) in tau.iter_mut().enumerate() {
        let uniform = ((k as f64 * frequency).sin() * 43758.5453).rem_euclid(1.0);
        *t += amplitude * (2.0 * uniform - 1.0);
    }
    [q, qd, qdd, tau]
}

/// The identification samples of a 7-joint recording `[q, qdot, qddot, tau]`.
fn samples(r: &[Vec<f64>; 4]) -> Samples<'_> {
    Samples {
        q: &r[0],
        qdot: &r[1],
        qddot: &r[2],
        tau: &r[3],
        dof: 7,
    }
}

#[test]
fn noisy_torques_are_not_fitted_to_the_noise() {
    let urdf = common::baxter();
    // Deterministic pseudo-noise, 1 N m.
    let recording = noisy_recording(&urdf, 40.0, 12.9898, 1.0);
    let train = samples(&recording);
    let ident = identify(&urdf, &train, None, &IdentificationSettings::default()).unwrap();
    // Held-out error is about the noise (uniform on +-1: rms 0.577), not below it.
    for e in &ident.summary.expected_false_torque_rms {
        assert!(
            *e > 0.5 && *e < 0.8,
            "{:?}",
            ident.summary.expected_false_torque_rms
        );
    }
}

#[test]
fn a_ridge_tolerance_takes_the_strongest_ridge_near_the_best() {
    let urdf = common::baxter();
    let recording = noisy_recording(&urdf, 30.0, 78.233, 0.5);
    let train = samples(&recording);
    let fit = |tolerance: f64| {
        let settings = IdentificationSettings {
            ridge_tolerance: tolerance,
            springs: false,
            ..Default::default()
        };
        identify(&urdf, &train, None, &settings).unwrap()
    };
    let total = |i: &Identification| -> f64 {
        i.summary
            .expected_false_torque_rms
            .iter()
            .map(|e| e * e)
            .sum()
    };
    let (best, near) = (fit(0.0), fit(0.05));
    assert!(
        near.summary.ridge > best.summary.ridge,
        "{} {}",
        near.summary.ridge,
        best.summary.ridge
    );
    // The held-out error it accepts: within the tolerance of the best (squared errors, as
    // the choice compares them), and more than the best's (else it would be the best).
    let (b, n) = (total(&best), total(&near));
    assert!(n <= 1.05 * b * 1.000001 && n >= b * 0.999999, "{n} {b}");
    assert!(near.joint_terms.iter().all(|t| t.is_physical()));
    let bad = IdentificationSettings {
        ridge_tolerance: 0.7,
        ..Default::default()
    };
    let e = identify(&urdf, &train, None, &bad).unwrap_err().to_string();
    assert!(e.contains("ridge_tolerance"), "{e}");
}

#[test]
fn bad_samples_and_settings_are_named() {
    let urdf = common::baxter();
    let (q, qd, qdd) = motion(&urdf, 0.3, 2.0);
    let mut tau = vec![0.0; q.len()];
    tau[7 * 10 + 3] = f64::NAN;
    let train = Samples {
        q: &q,
        qdot: &qd,
        qddot: &qdd,
        tau: &tau,
        dof: 7,
    };
    let e = identify(&urdf, &train, None, &IdentificationSettings::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("tau of joint 3 at sample 10"), "{e}");
    let short = Samples {
        q: &q[..6],
        ..train
    };
    assert!(identify(&urdf, &short, None, &IdentificationSettings::default()).is_err());
    let bad = IdentificationSettings {
        folds: 1,
        ..Default::default()
    };
    let e = identify(&urdf, &train, None, &bad).unwrap_err().to_string();
    assert!(e.contains("folds"), "{e}");
    let bad = IdentificationSettings {
        max_mass_ratio: Some(0.5),
        ..Default::default()
    };
    let e = identify(&urdf, &train, None, &bad).unwrap_err().to_string();
    assert!(
        e.contains("max_mass_ratio") && e.contains("at least 1"),
        "{e}"
    );
    // No torque recorded (a missing column read as zeros): refused, not a massless arm.
    let zeros = vec![0.0; q.len()];
    let e = identify(
        &urdf,
        &Samples {
            tau: &zeros,
            ..train
        },
        None,
        &IdentificationSettings::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("torque is 0 in every sample"), "{e}");
}

#[test]
fn files_round_trip_and_refuse_damage_and_other_arms() {
    let urdf = common::baxter();
    let (q, qd, qdd) = motion(&urdf, 0.5, 20.0);
    let tau = torques(&urdf, &truth_terms(7), &q, &qd, &qdd);
    let train = Samples {
        q: &q,
        qdot: &qd,
        qddot: &qdd,
        tau: &tau,
        dof: 7,
    };
    let ident = identify(&urdf, &train, None, &IdentificationSettings::default()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("baxter.ident.json");
    let mut data = BTreeMap::new();
    data.insert("data".into(), serde_json::json!("synthetic"));
    ident.save(&path, &urdf, data.clone()).unwrap();
    let back = Identification::load(&path, &urdf).unwrap();
    assert_eq!(back.joint_terms, ident.joint_terms);
    assert_eq!(
        inertial_parameters(&back.model),
        inertial_parameters(&ident.model)
    );
    let (again, model) = Identification::load_with_urdf(&path).unwrap();
    assert_eq!(model.fingerprint(), urdf.fingerprint());
    assert_eq!(again.summary, ident.summary);
    // Another arm is refused.
    let other = urdf.with_scaled_inertias(2.0).unwrap();
    let e = Identification::load(&path, &other).unwrap_err().to_string();
    assert!(e.contains("another arm"), "{e}");
    // A changed number is caught by the checksum.
    let text = std::fs::read_to_string(&path).unwrap();
    let tampered = text.replacen("\"ridge\": ", "\"ridge\": 1", 1);
    std::fs::write(&path, tampered).unwrap();
    let e = Identification::load(&path, &urdf).unwrap_err().to_string();
    assert!(e.contains("checksum"), "{e}");
    // A user's file is not overwritten.
    let user = dir.path().join("notes.json");
    std::fs::write(&user, "{\"mine\": 1}").unwrap();
    assert!(ident.save(&user, &urdf, data).is_err());
    assert_eq!(std::fs::read_to_string(&user).unwrap(), "{\"mine\": 1}");
}

/// Rms error of `ident`'s prediction against `tau` on the motion `(q, qd, qdd)`.
fn prediction_error(ident: &Identification, [q, qd, qdd, tau]: &[Vec<f64>; 4]) -> f64 {
    let n = ident.model.nq();
    let mut data = Data::new(&ident.model);
    let mut out = vec![0.0; n];
    let mut pred = Vec::with_capacity(tau.len());
    for k in 0..q.len() / n {
        let r = k * n..(k + 1) * n;
        ident
            .predict(&mut data, &q[r.clone()], &qd[r.clone()], &qdd[r], &mut out)
            .unwrap();
        pred.extend_from_slice(&out);
    }
    rms(&pred, tau)
}

#[test]
fn a_torque_of_another_size_than_the_urdf_scales_the_prior() {
    let urdf = common::baxter();
    // A torque signal 8 % larger than the URDF's arm gives (a torque constant off), noisy.
    let scaled = |mut r: [Vec<f64>; 4]| {
        r[3].iter_mut().for_each(|t| *t *= 1.08);
        r
    };
    let train = scaled(noisy_recording(&urdf, 30.0, 78.233, 0.5));
    let (q2, qd2, qdd2) = motion(&urdf, 1.7, 20.0);
    let tau2 = torques(&urdf, &truth_terms(7), &q2, &qd2, &qdd2);
    let new_motion = [q2, qd2, qdd2, tau2];
    let new_scaled = scaled(new_motion.clone());
    let fit = |r: &[Vec<f64>; 4], tolerance: f64| {
        let settings = IdentificationSettings {
            ridge_tolerance: tolerance,
            ..Default::default()
        };
        identify(&urdf, &samples(r), None, &settings).unwrap()
    };
    let mass = |m: &Model| m.bodies.iter().map(|b| b.mass).sum::<f64>();
    for tolerance in [0.0, 0.05] {
        let ident = fit(&train, tolerance);
        let s = ident.summary.prior_scale;
        let ratio = mass(&ident.model) / mass(&urdf);
        assert!(
            (s - 1.08).abs() < 0.005,
            "tolerance {tolerance}: prior_scale {s}"
        );
        assert!(
            (ratio - 1.08).abs() < 0.01,
            "tolerance {tolerance}: mass ratio {ratio}"
        );
        // On new motion as good as the same recording at the URDF's size, scaled.
        let at_size = fit(&noisy_recording(&urdf, 30.0, 78.233, 0.5), tolerance);
        assert_eq!(at_size.summary.prior_scale, 1.0);
        let err = prediction_error(&ident, &new_scaled);
        let reference = 1.08 * prediction_error(&at_size, &new_motion);
        assert!(
            err < 1.1 * reference,
            "tolerance {tolerance}: {err} vs {reference}"
        );
    }
}

/// A recording that barely moves the joints (3 % of the motion above, each joint about its
/// mid-range) leaves the URDF's gravity torque nearly constant, where the offsets take it:
/// the torque's size cannot be read there, and is neither applied nor refused.
#[test]
fn a_recording_that_barely_moves_reads_no_torque_size() {
    let urdf = common::baxter();
    let n = urdf.nq();
    let (mut q, mut qd, mut qdd) = motion(&urdf, 0.9, 10.0);
    for (k, ((p, v), a)) in q.iter_mut().zip(&mut qd).zip(&mut qdd).enumerate() {
        let j = &urdf.joints[k % n];
        let mid = 0.5 * (j.limits.lower + j.limits.upper);
        *p = mid + 0.03 * (*p - mid);
        *v *= 0.03;
        *a *= 0.03;
    }
    let mut tau = torques(&urdf, &truth_terms(n), &q, &qd, &qdd);
    for (k, t) in tau.iter_mut().enumerate() {
        *t += 0.5 * (2.0 * ((k as f64 * 78.233).sin() * 43758.5453).rem_euclid(1.0) - 1.0);
    }
    let r = [q, qd, qdd, tau];
    let ident = identify(
        &urdf,
        &samples(&r),
        None,
        &IdentificationSettings::default(),
    )
    .unwrap();
    assert_eq!(ident.summary.prior_scale, 1.0);
}

/// A recording that cannot be of the URDF's arm as written is refused, naming the joint or
/// the unit: angles in degrees, one joint's torque sign flipped, a torque in mN m.
#[test]
fn recordings_that_cannot_be_the_urdfs_arm_are_refused() {
    let urdf = common::baxter();
    let [q, qd, qdd, tau] = noisy_recording(&urdf, 20.0, 12.9898, 0.1);
    let fit = |q: &[f64], qd: &[f64], qdd: &[f64], tau: &[f64]| {
        let r = [q.to_vec(), qd.to_vec(), qdd.to_vec(), tau.to_vec()];
        identify(
            &urdf,
            &samples(&r),
            None,
            &IdentificationSettings::default(),
        )
        .map(|_| ())
        .map_err(|e| e.to_string())
    };
    assert_eq!(fit(&q, &qd, &qdd, &tau), Ok(()));
    let degrees = |v: &[f64]| v.iter().map(|x| x.to_degrees()).collect::<Vec<_>>();
    let e = fit(&degrees(&q), &degrees(&qd), &degrees(&qdd), &tau).unwrap_err();
    assert!(
        e.contains("beyond its URDF limits") && e.contains("radians"),
        "{e}"
    );
    let mut flipped = tau.clone();
    flipped.iter_mut().skip(1).step_by(7).for_each(|t| *t = -*t);
    let e = fit(&q, &qd, &qdd, &flipped).unwrap_err();
    assert!(e.contains("joint left_s1's torque runs opposite"), "{e}");
    let milli: Vec<f64> = tau.iter().map(|t| 1e3 * t).collect();
    let e = fit(&q, &qd, &qdd, &milli).unwrap_err();
    assert!(
        e.contains("training samples: the recorded torque is 999.") && e.contains("in N m"),
        "{e}"
    );
}

/// A torque the model cannot describe (a 40 N m gravity-assist spring on the shoulder,
/// springs not offered) on a narrow motion: unbounded, the fit makes a link heavier than
/// twice the URDF's to mimic it; bounded (the default) every body stays within its mass
/// bound and the summary names the bodies held there.
#[test]
fn bodies_stay_the_arms_size_and_those_held_there_are_named() {
    let urdf = common::baxter();
    let (q, qd, qdd) = motion(&urdf, 0.7, 30.0);
    let mut terms = truth_terms(urdf.nq());
    terms[1].spring = [0.0, 40.0, 0.0, 0.0];
    let tau = torques(&urdf, &terms, &q, &qd, &qdd);
    let train = Samples {
        q: &q,
        qdot: &qd,
        qddot: &qdd,
        tau: &tau,
        dof: urdf.nq(),
    };
    let settings = |ratio| IdentificationSettings {
        springs: false,
        max_mass_ratio: ratio,
        ..Default::default()
    };
    let urdf_mass: Vec<f64> = urdf.bodies.iter().map(|b| b.mass).collect();
    let arm: f64 = urdf_mass.iter().sum();
    let over = |ident: &Identification| -> Vec<usize> {
        let scale = ident.summary.prior_scale;
        (0..urdf.nq())
            .filter(|&b| {
                ident.model.bodies[b].mass > scale * (2.0 * urdf_mass[b] + 0.05 * arm) * 1.0001
            })
            .collect()
    };
    let free = identify(&urdf, &train, None, &settings(None)).unwrap();
    assert!(
        !over(&free).is_empty(),
        "{:?}",
        free.model.bodies.iter().map(|b| b.mass).collect::<Vec<_>>()
    );
    assert!(free.summary.bodies_at_extent.is_empty());
    let bounded = identify(&urdf, &train, None, &settings(Some(2.0))).unwrap();
    assert!(
        over(&bounded).is_empty(),
        "{:?}",
        bounded
            .model
            .bodies
            .iter()
            .map(|b| b.mass)
            .collect::<Vec<_>>()
    );
    assert!(!bounded.summary.bodies_at_extent.is_empty());
    assert!(bounded.joint_terms.iter().all(|t| t.is_physical()));
}

/// A torque signal 10 ms late against the motion (a torque filter, a series-elastic joint):
/// `identify` finds the delay on held-out stretches of one recording, every stretch gaining,
/// and takes none where there is none.
#[test]
fn a_late_torque_signal_is_found_and_none_where_there_is_none() {
    let urdf = common::baxter();
    let terms = truth_terms(7);
    let (q, qd, qdd) = motion(&urdf, 0.3, 30.0);
    let tau = torques(&urdf, &terms, &q, &qd, &qdd);
    let settings = IdentificationSettings {
        sample_rate_hz: Some(200.0),
        ..Default::default()
    };
    for lag in [0usize, 2] {
        // The torque recorded with the motion's row k is the one of row k - lag.
        let rows = q.len() / 7 - lag;
        let train = Samples {
            q: &q[7 * lag..],
            qdot: &qd[7 * lag..],
            qddot: &qdd[7 * lag..],
            tau: &tau[..7 * rows],
            dof: 7,
        };
        let ident = identify(&urdf, &train, None, &settings).unwrap();
        let delay = ident.summary.delay_s[0];
        assert!(
            (delay - lag as f64 / 200.0).abs() < 1e-9,
            "{lag} samples late: delay {delay} s"
        );
    }
}

/// A recorded acceleration carrying differentiation noise several times the motion's own
/// (as a 100 Hz recording's second difference does): regressed on as measured, the noise
/// biases the physical fit's gravity and friction; the fit's zero-phase smoothed acceleration
/// (`fit_acceleration_hz`, the default) keeps them. Judged on new motion through the torque
/// at zero acceleration, which the acceleration gain does not touch.
#[test]
fn a_noisy_acceleration_does_not_bias_the_fit() {
    let urdf = common::baxter();
    let truth = heavier_baxter(&urdf);
    let terms = truth_terms(7);
    // Uniform pseudo-noise of +-5 rad/s^2 on every recorded acceleration.
    let recording = noisy_acceleration_recording(&urdf, &truth, 0.3, 5.0);
    let train = samples(&recording);
    let (q2, qd2, _) = motion(&urdf, 0.7, 20.0);
    let zero = vec![0.0; q2.len()];
    let want = torques(&truth, &terms, &q2, &qd2, &zero);
    let error = |fit_acceleration_hz: Option<f64>| {
        let settings = IdentificationSettings {
            sample_rate_hz: Some(200.0),
            fit_acceleration_hz,
            ..Default::default()
        };
        let ident = identify(&urdf, &train, None, &settings).unwrap();
        let mut data = Data::new(&urdf);
        let mut got = vec![0.0; q2.len()];
        for (k, out) in got.chunks_exact_mut(7).enumerate() {
            let r = 7 * k..7 * (k + 1);
            ident
                .predict(&mut data, &q2[r.clone()], &qd2[r.clone()], &zero[r], out)
                .unwrap();
        }
        (rms(&got, &want), ident.summary.fit_acceleration_hz)
    };
    let (smoothed, hz) = error(IdentificationSettings::default().fit_acceleration_hz);
    let (as_measured, none) = error(None);
    assert_eq!((hz, none), (FIT_ACCELERATION_HZ, 0.0));
    eprintln!("torque at zero acceleration on new motion: {smoothed:.3} N m smoothed, {as_measured:.3} as measured");
    assert!(
        smoothed < 0.5 * as_measured,
        "smoothed {smoothed:.3} N m against {as_measured:.3} as measured"
    );
}

/// 40 s of the motion of `seed` and `truth`'s torques, the recorded acceleration carrying
/// uniform pseudo-noise of +-`amplitude` rad/s^2: `[q, qdot, qddot, tau]`.
fn noisy_acceleration_recording(
    urdf: &Model,
    truth: &Model,
    seed: f64,
    amplitude: f64,
) -> [Vec<f64>; 4] {
    let (q, qd, qdd) = motion(urdf, seed, 40.0);
    let tau = torques(truth, &truth_terms(7), &q, &qd, &qdd);
    let noisy = with_noise(&qdd, 12.9898, amplitude);
    [q, qd, noisy, tau]
}

/// `qdd` with uniform pseudo-noise of +-`amplitude` rad/s^2 (`frequency` picks the sequence).
fn with_noise(qdd: &[f64], frequency: f64, amplitude: f64) -> Vec<f64> {
    qdd.iter()
        .enumerate()
        .map(|(k, a)| {
            let uniform = ((k as f64 * frequency).sin() * 43758.5453).rem_euclid(1.0);
            a + amplitude * (2.0 * uniform - 1.0)
        })
        .collect()
}

/// Trained on slow motion whose recorded acceleration is mostly noise, the held-out gain on
/// `q''` is small; over faster motion `predict_motion` takes more of it where the motion
/// accelerates well beyond that noise, and stays near the gain on motion as slow as the
/// training's.
#[test]
fn the_acceleration_gain_rises_on_motion_faster_than_the_training() {
    let urdf = common::baxter();
    let truth = heavier_baxter(&urdf);
    let terms = truth_terms(7);
    // Seed -2.5: a quarter of the speed of seed 0 (the motion's frequencies scale with it).
    let recording = noisy_acceleration_recording(&urdf, &truth, -2.5, 0.5);
    let train = samples(&recording);
    let settings = IdentificationSettings {
        sample_rate_hz: Some(200.0),
        ..Default::default()
    };
    let ident = identify(&urdf, &train, None, &settings).unwrap();
    let gain = ident.summary.acceleration_gain;
    assert!(gain < 0.5, "gain {gain}");
    assert_eq!(ident.summary.acceleration_power.len(), 7);
    let errors = |seed: f64| {
        let (q2, qd2, qdd2) = motion(&urdf, seed, 20.0);
        let want = torques(&truth, &terms, &q2, &qd2, &qdd2);
        let measured = with_noise(&qdd2, 78.233, 0.5);
        let fixed = prediction_error(
            &ident,
            &[q2.clone(), qd2.clone(), measured.clone(), want.clone()],
        );
        let mut motion_wise = vec![0.0; q2.len()];
        ident
            .predict_motion(&q2, &qd2, &measured, &mut motion_wise)
            .unwrap();
        (fixed, rms(&motion_wise, &want))
    };
    let (fixed, rising) = errors(1.0);
    eprintln!(
        "gain {gain}; faster motion: {fixed:.3} N m with the gain, {rising:.3} over the motion"
    );
    assert!(rising < 0.5 * fixed, "{rising:.3} against {fixed:.3}");
    let (fixed, rising) = errors(-2.4);
    eprintln!("motion as slow: {fixed:.3} N m with the gain, {rising:.3} over the motion");
    assert!(rising < 1.02 * fixed, "{rising:.3} against {fixed:.3}");
}
