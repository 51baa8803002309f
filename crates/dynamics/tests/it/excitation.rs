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

/// The URDF's whole range and limits (the envelope before issue 30, for simulations).
fn whole_range() -> ExcitationSettings {
    ExcitationSettings {
        range: vec![f64::INFINITY],
        velocity_fraction: 1.0,
        acceleration_fraction: 1.0,
        ..Default::default()
    }
}

fn short() -> ExcitationSettings {
    ExcitationSettings {
        duration: 20.0,
        ..whole_range()
    }
}

/// Joint `i`'s position interval: `range` around `pose` (default: the middle of the
/// limits) inside the limits less the margin.
fn envelope(model: &Model, settings: &ExcitationSettings, i: usize) -> (f64, f64) {
    let l = &model.joints[i].limits;
    let m = settings.position_margin * (l.upper - l.lower);
    let pose = settings
        .pose
        .get(i)
        .copied()
        .unwrap_or(0.5 * (l.lower + l.upper));
    let range = if settings.range.len() == 1 {
        settings.range[0]
    } else {
        settings.range[i]
    };
    (
        (pose - range).max(l.lower + m),
        (pose + range).min(l.upper - m),
    )
}

/// Every sample inside the envelope (positions, velocities, accelerations); at rest at
/// both ends; the columns consistent with each other.
fn check_limits(model: &Model, settings: &ExcitationSettings, e: &Excitation) {
    let n = model.nq();
    assert_eq!(e.q.len(), e.len() * n);
    assert_eq!(
        e.len(),
        (settings.duration * settings.rate_hz).round() as usize + 1
    );
    for (i, j) in model.joints.iter().enumerate() {
        let l = &j.limits;
        let (lowest, highest) = envelope(model, settings, i);
        let vurdf = if l.velocity.is_finite() {
            l.velocity
        } else {
            DEFAULT_VELOCITY_LIMIT
        };
        let vmax = settings.velocity_fraction * vurdf;
        let amax = settings.acceleration_fraction * settings.acceleration_limit;
        for k in 0..e.len() {
            let (q, v, a) = (e.q[k * n + i], e.qdot[k * n + i], e.qddot[k * n + i]);
            assert!(
                q >= lowest - 1e-12 && q <= highest + 1e-12,
                "joint {i} sample {k}: q {q} outside [{lowest}, {highest}]"
            );
            assert!(
                v.abs() <= vmax * (1.0 + 1e-12),
                "joint {i} sample {k}: qdot {v} over {vmax}"
            );
            assert!(
                a.abs() <= amax * (1.0 + 1e-12),
                "joint {i} sample {k}: qddot {a} over {amax}"
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
                (dq - e.qdot[k * n + i]).abs() < 1e-3 * vurdf,
                "joint {i} sample {k}: dq {dq} vs {}",
                e.qdot[k * n + i]
            );
        }
    }
    let uses = e.limit_use(model, settings);
    assert!(uses
        .iter()
        .all(|u| u.position <= 1.0 + 1e-12 && u.velocity <= 1.0 + 1e-12));
    // Every joint reaches at least one of its limits: the motion is as large as allowed.
    for u in &uses {
        let most = u.position.max(u.velocity).max(u.acceleration);
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
        ..whole_range()
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
            ..whole_range()
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
    let truth = crate::identification::heavier_baxter(&urdf);
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
        ..whole_range()
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

/// A UR5 (kinematics, masses, inertias and limits as example-robot-data 6.0.0's
/// `ur_description/urdf/ur5_robot.urdf` states them: +-2 pi on every joint but the elbow's
/// +-pi, 3.15 and 3.2 rad/s), base_link to tool0.
fn ur5() -> Model {
    // (joint, parent, child, joint origin xyz, rpy, axis, child mass, com z, ixx=iyy, izz)
    let chain = [
        (
            "shoulder_pan_joint",
            "base_link",
            "shoulder_link",
            "0 0 0.089159",
            "0 0 0",
            "0 0 1",
            3.7,
            0.0,
            0.010267495893,
            0.00666,
            6.28318530718,
            3.15,
        ),
        (
            "shoulder_lift_joint",
            "shoulder_link",
            "upper_arm_link",
            "0 0.13585 0",
            "0 1.57079632679 0",
            "0 1 0",
            8.393,
            0.28,
            0.22689067591,
            0.0151074,
            6.28318530718,
            3.15,
        ),
        (
            "elbow_joint",
            "upper_arm_link",
            "forearm_link",
            "0 -0.1197 0.425",
            "0 0 0",
            "0 1 0",
            2.275,
            0.25,
            0.049443313556,
            0.004095,
            3.14159265359,
            3.15,
        ),
        (
            "wrist_1_joint",
            "forearm_link",
            "wrist_1_link",
            "0 0 0.39225",
            "0 1.57079632679 0",
            "0 1 0",
            1.219,
            0.0,
            0.111172755531,
            0.21942,
            6.28318530718,
            3.2,
        ),
        (
            "wrist_2_joint",
            "wrist_1_link",
            "wrist_2_link",
            "0 0.093 0",
            "0 0 0",
            "0 0 1",
            1.219,
            0.0,
            0.111172755531,
            0.21942,
            6.28318530718,
            3.2,
        ),
        (
            "wrist_3_joint",
            "wrist_2_link",
            "wrist_3_link",
            "0 0 0.09465",
            "0 0 0",
            "0 1 0",
            0.1879,
            0.0,
            0.0171364731454,
            0.033822,
            6.28318530718,
            3.2,
        ),
    ];
    let mut text = String::from(
        "<robot name=\"ur5\"><link name=\"base_link\"><inertial><mass value=\"4.0\"/><origin xyz=\"0 0 0\"/>\
         <inertia ixx=\"0.00443333156\" ixy=\"0\" ixz=\"0\" iyy=\"0.00443333156\" iyz=\"0\" izz=\"0.0072\"/></inertial></link>\n",
    );
    for (joint, parent, child, xyz, rpy, axis, mass, com_z, ixx, izz, limit, velocity) in chain {
        text += &format!(
            "<joint name=\"{joint}\" type=\"revolute\"><parent link=\"{parent}\"/><child link=\"{child}\"/>\
             <origin xyz=\"{xyz}\" rpy=\"{rpy}\"/><axis xyz=\"{axis}\"/>\
             <limit effort=\"150\" lower=\"-{limit}\" upper=\"{limit}\" velocity=\"{velocity}\"/></joint>\n\
             <link name=\"{child}\"><inertial><mass value=\"{mass}\"/><origin xyz=\"0 0 {com_z}\"/>\
             <inertia ixx=\"{ixx}\" ixy=\"0\" ixz=\"0\" iyy=\"{ixx}\" iyz=\"0\" izz=\"{izz}\"/></inertial></link>\n"
        );
    }
    text += "<joint name=\"wrist_3_link-tool0_fixed_joint\" type=\"fixed\"><parent link=\"wrist_3_link\"/>\
             <child link=\"tool0\"/><origin xyz=\"0 0.0823 0\" rpy=\"-1.57079632679 0 0\"/></joint>\
             <link name=\"tool0\"/></robot>";
    Model::from_urdf_str(&text, "ur5 (test)", Some("base_link"), Some("tool0"))
        .expect("the UR5 loads")
}

#[test]
fn a_ur5_excitation_stays_inside_the_stated_envelope_at_every_sample() {
    let model = ur5();
    assert_eq!(model.nq(), 6);
    // The default envelope: +-0.5 rad around the middle of the limits, 30 % of the
    // velocity and acceleration limits.
    let default = ExcitationSettings {
        duration: 20.0,
        iterations: 200,
        ..Default::default()
    };
    let e = excitation(&model, &default).unwrap();
    check_limits(&model, &default, &e);
    for k in 0..e.len() {
        for i in 0..6 {
            assert!(e.q[k * 6 + i].abs() <= 0.5 + 1e-12, "joint {i} sample {k}");
        }
    }
    // A stated pose, one range per joint, other fractions.
    let pose = vec![0.3, -1.57, 1.57, -1.57, -1.57, 0.0];
    let stated = ExcitationSettings {
        pose: pose.clone(),
        range: vec![0.4, 0.3, 0.3, 0.6, 0.6, 1.0],
        velocity_fraction: 0.2,
        acceleration_fraction: 0.5,
        ..default.clone()
    };
    let e = excitation(&model, &stated).unwrap();
    check_limits(&model, &stated, &e);
    for k in 0..e.len() {
        for i in 0..6 {
            let d = (e.q[k * 6 + i] - pose[i]).abs();
            assert!(
                d <= stated.range[i] + 1e-12,
                "joint {i} sample {k}: {d} from the pose"
            );
        }
    }
    eprintln!(
        "UR5, stated envelope: condition number {:.1}; limit use {:?}",
        e.condition_number,
        e.limit_use(&model, &stated)
    );
    // A pose near a limit: the range is cut at the limit less the margin.
    let near = ExcitationSettings {
        pose: vec![0.0, 0.0, 2.7, 0.0, 0.0, 0.0],
        range: vec![0.5],
        ..default
    };
    let e = excitation(&model, &near).unwrap();
    check_limits(&model, &near, &e);
}

#[test]
fn bad_envelopes_are_named() {
    let model = ur5();
    let cases = [
        (
            ExcitationSettings {
                range: vec![],
                ..Default::default()
            },
            "range",
        ),
        (
            ExcitationSettings {
                range: vec![0.5, -1.0, 0.5, 0.5, 0.5, 0.5],
                ..Default::default()
            },
            "range",
        ),
        (
            ExcitationSettings {
                range: vec![0.5, 0.5],
                ..Default::default()
            },
            "range",
        ),
        (
            ExcitationSettings {
                pose: vec![0.0; 5],
                ..Default::default()
            },
            "pose",
        ),
        (
            ExcitationSettings {
                pose: vec![0.0, 0.0, 4.0, 0.0, 0.0, 0.0],
                ..Default::default()
            },
            "pose",
        ),
        (
            ExcitationSettings {
                pose: vec![f64::NAN; 6],
                ..Default::default()
            },
            "pose",
        ),
        (
            ExcitationSettings {
                velocity_fraction: 1.5,
                ..Default::default()
            },
            "velocity_fraction",
        ),
        (
            ExcitationSettings {
                acceleration_fraction: 0.0,
                ..Default::default()
            },
            "acceleration_fraction",
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
}
