//! Excitation trajectories stay inside the limits on every sample, start and end at rest,
//! excite the base parameters better than a random series, repeat for a seed, name bad
//! settings, and let identification recover an arm from them.

use crate::common;
use admittance_dynamics::*;

fn panda() -> Model {
    Model::from_urdf_file(
        &common::repo_root().join("models/franka_panda.urdf"),
        None,
        None,
    )
    .expect("the Panda loads")
}

fn short() -> ExcitationSettings {
    ExcitationSettings {
        duration: 20.0,
        ..Default::default()
    }
}

/// Every sample inside the position range less the margin, the velocity limit and the
/// acceleration limit; at rest at both ends; the columns consistent with each other.
fn check_limits(model: &Model, settings: &ExcitationSettings, e: &Excitation) {
    let n = model.nq();
    assert_eq!(e.q.len(), e.len() * n);
    assert_eq!(
        e.len(),
        (settings.duration * settings.rate_hz).round() as usize + 1
    );
    for (i, j) in model.joints.iter().enumerate() {
        let l = &j.limits;
        let m = settings.position_margin * (l.upper - l.lower);
        let vmax = if l.velocity.is_finite() {
            l.velocity
        } else {
            DEFAULT_VELOCITY_LIMIT
        };
        for k in 0..e.len() {
            let (q, v, a) = (e.q[k * n + i], e.qdot[k * n + i], e.qddot[k * n + i]);
            assert!(
                q >= l.lower + m - 1e-12 && q <= l.upper - m + 1e-12,
                "joint {i} sample {k}: q {q} outside [{}, {}]",
                l.lower + m,
                l.upper - m
            );
            assert!(
                v.abs() <= vmax * (1.0 + 1e-12),
                "joint {i} sample {k}: qdot {v} over {vmax}"
            );
            assert!(
                a.abs() <= settings.acceleration_limit * (1.0 + 1e-12),
                "joint {i} sample {k}: qddot {a}"
            );
        }
        for k in [0, e.len() - 1] {
            assert!(
                e.qdot[k * n + i].abs() < 1e-9 && e.qddot[k * n + i].abs() < 1e-9,
                "joint {i} not at rest at sample {k}"
            );
        }
        // Central differences of q and qdot match qdot and qddot.
        let h = 1.0 / settings.rate_hz;
        for k in 1..e.len() - 1 {
            let dq = (e.q[(k + 1) * n + i] - e.q[(k - 1) * n + i]) / (2.0 * h);
            assert!(
                (dq - e.qdot[k * n + i]).abs() < 1e-3 * vmax,
                "joint {i} sample {k}: dq {dq} vs {}",
                e.qdot[k * n + i]
            );
        }
    }
    let uses = e.limit_use(model, settings);
    assert!(uses.iter().all(
        |u| u.position <= 1.0 - 2.0 * settings.position_margin + 1e-12 && u.velocity <= 1.0 + 1e-12
    ));
    // Every joint reaches at least one of its limits: the motion is as large as allowed.
    for u in &uses {
        let most = (u.position / (1.0 - 2.0 * settings.position_margin))
            .max(u.velocity)
            .max(u.acceleration);
        assert!(most > 0.99, "{uses:?}");
    }
}

#[test]
fn baxter_and_panda_stay_inside_their_limits_and_beat_a_random_series() {
    for (name, model) in [("baxter", common::baxter()), ("panda", panda())] {
        let settings = short();
        let started = std::time::Instant::now();
        let e = excitation(&model, &settings).unwrap();
        eprintln!(
            "{name}: condition number {:.1} (random start {:.1}), {} base parameters, {:.2} s",
            e.condition_number,
            e.initial_condition_number,
            e.base_parameters,
            started.elapsed().as_secs_f64()
        );
        check_limits(&model, &settings, &e);
        assert!(
            e.condition_number < 0.7 * e.initial_condition_number,
            "{name}: {} vs {}",
            e.condition_number,
            e.initial_condition_number
        );
        // The reported number is the base regressor's over the samples, as identification
        // computes it.
        let mut data = Data::new(&model);
        let n = model.nq();
        let base = BaseParameters::new(&model, 100, 1).unwrap();
        let rows: Vec<usize> = (0..e.len()).step_by(4).collect();
        let mut stacked = nalgebra::DMatrix::zeros(rows.len() * n, 10 * n);
        for (r, &k) in rows.iter().enumerate() {
            let s = k * n..(k + 1) * n;
            let y = joint_torque_regressor(
                &model,
                &mut data,
                &e.q[s.clone()],
                &e.qdot[s.clone()],
                &e.qddot[s],
            )
            .unwrap();
            stacked.view_mut((r * n, 0), (n, 10 * n)).copy_from(y);
        }
        let direct = base.condition_number(&stacked);
        assert!(
            (direct / e.condition_number - 1.0).abs() < 0.05,
            "{name}: {direct} vs {}",
            e.condition_number
        );
    }
}

#[test]
fn the_same_seed_gives_the_same_motion_and_another_seed_another() {
    let model = common::baxter();
    let settings = ExcitationSettings {
        duration: 10.0,
        iterations: 60,
        ..Default::default()
    };
    let a = excitation(&model, &settings).unwrap();
    let b = excitation(&model, &settings).unwrap();
    assert_eq!(a.q, b.q);
    assert_eq!(a.qddot, b.qddot);
    assert_eq!(a.series, b.series);
    assert_eq!(a.condition_number, b.condition_number);
    let c = excitation(
        &model,
        &ExcitationSettings {
            seed: 2,
            ..settings.clone()
        },
    )
    .unwrap();
    assert_ne!(a.q, c.q);
    // Several periods repeat the first.
    let long = excitation(
        &model,
        &ExcitationSettings {
            duration: 30.0,
            ..settings
        },
    )
    .unwrap();
    let n = model.nq();
    for k in [1, 500, 1999] {
        for i in 0..n {
            let (x, y) = (long.q[k * n + i], long.q[(k + 2000) * n + i]);
            assert!((x - y).abs() < 1e-9, "sample {k} joint {i}: {x} vs {y}");
        }
    }
    check_limits(
        &model,
        &ExcitationSettings {
            duration: 30.0,
            ..Default::default()
        },
        &long,
    );
}

#[test]
fn bad_settings_are_named() {
    let model = common::baxter();
    let cases = [
        (
            ExcitationSettings {
                duration: -1.0,
                ..Default::default()
            },
            "duration",
        ),
        (
            ExcitationSettings {
                period: 7.0,
                ..Default::default()
            },
            "period",
        ),
        (
            ExcitationSettings {
                period: 120.0,
                ..Default::default()
            },
            "period",
        ),
        (
            ExcitationSettings {
                harmonics: 1,
                ..Default::default()
            },
            "harmonics",
        ),
        (
            ExcitationSettings {
                rate_hz: 2.0,
                ..Default::default()
            },
            "rate_hz",
        ),
        (
            ExcitationSettings {
                rate_hz: 199.999,
                ..Default::default()
            },
            "rate_hz",
        ),
        (
            ExcitationSettings {
                acceleration_limit: f64::NAN,
                ..Default::default()
            },
            "acceleration_limit",
        ),
        (
            ExcitationSettings {
                position_margin: 0.5,
                ..Default::default()
            },
            "position_margin",
        ),
    ];
    for (settings, key) in cases {
        let Err(e) = excitation(&model, &settings) else {
            panic!("{key}: accepted")
        };
        let e = e.to_string();
        assert!(
            e.contains(&format!("excitation setting {key}")),
            "{key}: {e}"
        );
    }
    ExcitationSettings::default().validate().unwrap();
}

fn torques(model: &Model, terms: &[JointTerms], e: &Excitation) -> Vec<f64> {
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
        out.extend((0..n).map(|i| {
            tau[i] + terms[i].torque(e.q[k * n + i], e.qdot[k * n + i], e.qddot[k * n + i])
        }));
    }
    out
}

#[test]
fn identification_on_an_excitation_recovers_the_arm_on_other_motion() {
    let urdf = common::baxter();
    let truth = urdf
        .with_body_scales(&[1.3, 0.8, 1.2, 1.1, 0.9, 1.25, 1.1])
        .unwrap();
    let terms: Vec<JointTerms> = (0..7)
        .map(|i| JointTerms {
            armature: 0.05,
            viscous: 1.0 + 0.2 * i as f64,
            coulomb: [1.5, 0.3],
            coulomb_width: 0.01,
            offset: 0.2,
            ..Default::default()
        })
        .collect();
    let settings = ExcitationSettings {
        duration: 30.0,
        rate_hz: 100.0,
        ..Default::default()
    };
    let train = excitation(&urdf, &settings).unwrap();
    let tau = torques(&truth, &terms, &train);
    let samples = Samples {
        q: &train.q,
        qdot: &train.qdot,
        qddot: &train.qddot,
        tau: &tau,
        dof: 7,
    };
    let ident = identify(
        &urdf,
        &samples,
        None,
        &IdentificationSettings {
            springs: false,
            ..Default::default()
        },
    )
    .unwrap();
    // Other motion: another seed's excitation.
    let other = excitation(
        &urdf,
        &ExcitationSettings {
            seed: 9,
            duration: 10.0,
            iterations: 0,
            ..settings
        },
    )
    .unwrap();
    let want = torques(&truth, &terms, &other);
    let mut data = Data::new(&ident.model);
    let (mut out, mut sq, mut sq_urdf) = ([0.0; 7], 0.0, 0.0);
    let urdf_tau = torques(
        &urdf,
        &vec![
            JointTerms {
                coulomb_width: 0.01,
                ..Default::default()
            };
            7
        ],
        &other,
    );
    for k in 0..other.len() {
        let s = k * 7..(k + 1) * 7;
        ident
            .predict(
                &mut data,
                &other.q[s.clone()],
                &other.qdot[s.clone()],
                &other.qddot[s.clone()],
                &mut out,
            )
            .unwrap();
        sq += out
            .iter()
            .zip(&want[s.clone()])
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>();
        sq_urdf += urdf_tau[s.clone()]
            .iter()
            .zip(&want[s])
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>();
    }
    let (ours, prior) = (
        (sq / want.len() as f64).sqrt(),
        (sq_urdf / want.len() as f64).sqrt(),
    );
    eprintln!(
        "other motion rms: identified {ours:.4} N m, URDF {prior:.3} N m; condition {:.1} / {:.1}",
        train.condition_number, ident.summary.condition_number
    );
    assert!(ours < 0.02 * prior, "identified {ours} vs URDF {prior}");
}
