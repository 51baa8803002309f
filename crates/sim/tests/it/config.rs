//! Plant configuration from TOML: defaults, unknown keys, and validation errors that name
//! the offending key.

use crate::common;
use admittance_sim::*;
use common::*;

const FULL: &str = r#"
rate_hz = 5000.0
control_rate_hz = 1000.0
integrator = "rk4_split"
inertia_scale = 1.2
effort_limit_scale = 1.0
initial_q = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5]

[body_scales]
left_w2 = 1.5

[payload]
mass = 0.5
com = [0.0, 0.0, 0.05]
inertia = [1e-4, 1e-4, 1e-4]

[[friction]]
joint = "*"
viscous = 0.7
coulomb = 0.5

[[friction]]
joint = "left_w2"
coulomb = 0.1
v_s = 0.02

[[deadzones]]
joint = "left_s0"
d_left = -0.49
d_right = 0.49

[spring]
enabled = true

[[environment.joint_springs]]
joints = ["left_s0"]
mass = [0.01]
damping = [0.15]
stiffness = [1.1]
t_start = 12.0
t_end = 30.0

[[environment.walls]]
point = [0.8, 0.2, 0.0]
normal = [0.0, 0.0, 1.0]
t_start = 1.0

[[environment.joint_torque_profiles]]
joint = "left_e1"
points = [[0.0, 0.0], [1.0, 2.0], [2.0, 0.0]]

[[environment.tip_force_profiles]]
points = [[5.0, 0.0, 0.0, 0.0], [6.0, 10.0, 0.0, 0.0]]
t_end = inf

[sensors]
resolution_rad = 1e-5
noise_std = 1e-4
seed = 7
filter_cutoff_hz = 20.0

[[sensors.faults]]
kind = "stale"
joints = ["left_s0"]
t_start = 3.0
t_end = 3.002
"#;

fn parse(text: &str) -> Result<PlantConfig, toml::de::Error> {
    toml::from_str(text)
}

#[test]
fn a_full_configuration_parses_validates_and_builds() {
    let cfg = parse(FULL).unwrap();
    let model = baxter();
    cfg.validate(&model).unwrap();
    assert_eq!(cfg.substeps().unwrap(), 5);
    assert_eq!(cfg.friction.len(), 2);
    assert_eq!(cfg.environment.tip_force_profiles[0].t_end, f64::INFINITY);
    assert_eq!(cfg.environment.walls[0].t_end, f64::INFINITY);
    let plant = Plant::new(&model, &cfg).unwrap();
    // Later friction entries override earlier ones.
    assert_eq!(
        plant.friction()[0],
        Friction {
            viscous: 0.7,
            coulomb: 0.5,
            v_s: 0.01
        }
    );
    assert_eq!(
        plant.friction()[6],
        Friction {
            viscous: 0.0,
            coulomb: 0.1,
            v_s: 0.02
        }
    );
    assert_eq!(plant.deadzones()[0], Deadzone::symmetric(0.49));
    assert_eq!(plant.deadzones()[1], Deadzone::identity());
    // It round-trips.
    let again: PlantConfig = toml::from_str(&toml::to_string(&cfg).unwrap()).unwrap();
    assert_eq!(again, cfg);
}

#[test]
fn an_empty_file_is_the_ideal_plant() {
    let cfg = parse("").unwrap();
    assert_eq!(cfg, PlantConfig::default());
    assert_eq!(cfg.integrator, Integrator::Rk4Split);
    assert!(!cfg.spring.enabled && cfg.friction.is_empty() && cfg.environment.is_empty());
    Plant::new(&baxter(), &cfg).unwrap();
}

#[test]
fn unknown_keys_are_rejected_with_their_name() {
    for (text, key) in [
        ("rate = 5000.0", "rate"),
        ("[[friction]]\njoint = \"*\"\ncoulom = 0.5", "coulom"),
        ("[spring]\nenable = true", "enable"),
        (
            "[[environment.walls]]\nnormal = [0.0, 0.0, 1.0]\nstiff = 1.0",
            "stiff",
        ),
        ("[sensors]\nnoise = 0.1", "noise"),
        ("[environment]\nwall = []", "wall"),
        ("integrator = \"rk45\"", "rk45"),
    ] {
        let err = parse(text).unwrap_err().to_string();
        assert!(err.contains(key), "{text}: {err}");
    }
}

fn invalid(mutate: impl FnOnce(&mut PlantConfig)) -> SimError {
    let mut cfg = PlantConfig::default();
    mutate(&mut cfg);
    Plant::new(&baxter(), &cfg).expect_err("configuration should be rejected")
}

#[test]
fn invalid_values_name_their_key() {
    let cases: Vec<(SimError, &str)> = vec![
        (invalid(|c| c.rate_hz = -1.0), "rate_hz"),
        (invalid(|c| c.control_rate_hz = 0.0), "control_rate_hz"),
        (invalid(|c| c.rate_hz = 2500.0), "rate_hz"),
        (invalid(|c| c.inertia_scale = 0.0), "inertia_scale"),
        (invalid(|c| c.newton_tolerance = 0.0), "newton_tolerance"),
        (invalid(|c| c.newton_tolerance = 0.01), "newton_tolerance"),
        (
            invalid(|c| c.newton_tolerance = f64::NAN),
            "newton_tolerance",
        ),
        (
            invalid(|c| c.effort_limit_scale = f64::NAN),
            "effort_limit_scale",
        ),
        (
            invalid(|c| {
                c.friction = vec![FrictionConfig {
                    coulomb: -0.5,
                    ..Default::default()
                }]
            }),
            "friction[0].coulomb",
        ),
        (
            invalid(|c| {
                c.friction = vec![
                    FrictionConfig::default(),
                    FrictionConfig {
                        v_s: 0.0,
                        ..Default::default()
                    },
                ]
            }),
            "friction[1].v_s",
        ),
        (
            invalid(|c| {
                c.deadzones = vec![DeadzoneConfig {
                    d_left: 0.2,
                    ..Default::default()
                }]
            }),
            "deadzones[0].d_left",
        ),
        (
            invalid(|c| {
                c.deadzones = vec![DeadzoneConfig {
                    slope_right: -1.0,
                    ..Default::default()
                }]
            }),
            "deadzones[0].slope_right",
        ),
        (
            invalid(|c| {
                c.spring = SpringConfig {
                    enabled: true,
                    fraction: 1.5,
                    ..Default::default()
                }
            }),
            "spring.fraction",
        ),
        (
            invalid(|c| {
                c.payload = Some(PayloadConfig {
                    mass: -1.0,
                    ..Default::default()
                })
            }),
            "payload.mass",
        ),
        (invalid(|c| c.initial_q = vec![0.0; 3]), "initial_q"),
        (
            invalid(|c| c.sensors.filter_cutoff_hz = 600.0),
            "sensors.filter_cutoff_hz",
        ),
        (
            invalid(|c| c.sensors.noise_std = -1e-4),
            "sensors.noise_std",
        ),
        (
            invalid(|c| {
                c.sensors = SensorConfig {
                    resolution_rad: 1e-4,
                    counts_per_rev: 4096.0,
                    ..Default::default()
                }
            }),
            "sensors.counts_per_rev",
        ),
        (
            invalid(|c| {
                c.environment.joint_springs = vec![JointSpringConfig {
                    joints: vec!["left_s0".into()],
                    stiffness: vec![-1.1],
                    ..Default::default()
                }]
            }),
            "environment.joint_springs[0].stiffness[0]",
        ),
        (
            invalid(|c| {
                c.environment.joint_springs = vec![JointSpringConfig {
                    joints: vec!["left_s0".into(), "left_s1".into()],
                    mass: vec![0.1, 0.2, 0.3],
                    ..Default::default()
                }]
            }),
            "environment.joint_springs[0].mass",
        ),
        (
            invalid(|c| {
                c.environment.walls = vec![WallConfig {
                    normal: [0.0; 3],
                    ..Default::default()
                }]
            }),
            "environment.walls[0].normal",
        ),
        (
            invalid(|c| {
                c.environment.walls = vec![WallConfig {
                    t_start: 2.0,
                    t_end: 1.0,
                    ..Default::default()
                }]
            }),
            "environment.walls[0].t_end",
        ),
        (
            invalid(|c| {
                c.environment.joint_torque_profiles = vec![JointTorqueProfileConfig {
                    joint: "left_s0".into(),
                    points: vec![[1.0, 0.0], [0.5, 1.0]],
                    ..Default::default()
                }]
            }),
            "environment.joint_torque_profiles[0].points[1][0]",
        ),
        (
            invalid(|c| c.environment.tip_force_profiles = vec![TipForceProfileConfig::default()]),
            "environment.tip_force_profiles[0].points",
        ),
    ];
    for (err, key) in cases {
        assert_eq!(err.key(), Some(key), "{err}");
        assert!(
            err.to_string().starts_with(&format!("key `{key}`: ")),
            "{err}"
        );
    }
}

#[test]
fn unknown_joint_and_frame_names_are_reported_with_the_known_ones() {
    let err = invalid(|c| {
        c.deadzones = vec![DeadzoneConfig {
            joint: "left_s9".into(),
            ..Default::default()
        }]
    });
    assert_eq!(err.key(), Some("deadzones[0].joint"));
    let text = err.to_string();
    assert!(
        text.contains("left_s9") && text.contains("left_s0, left_s1"),
        "{text}"
    );
    let err = invalid(|c| {
        c.body_scales
            .insert("elbow".into(), 1.0)
            .map(|_| ())
            .unwrap_or(())
    });
    assert_eq!(err.key(), Some("body_scales.elbow"));
    let err = invalid(|c| {
        c.spring = SpringConfig {
            enabled: true,
            joint: "s1".into(),
            ..Default::default()
        }
    });
    assert_eq!(err.key(), Some("spring.joint"));
    let err = invalid(|c| {
        c.environment.walls = vec![WallConfig {
            frame: Some("left_palm".into()),
            ..Default::default()
        }]
    });
    assert_eq!(err.key(), Some("environment.walls[0].frame"));
    assert!(err.to_string().contains("left_hand"));
    let err = invalid(|c| {
        c.sensors.faults = vec![FaultConfig {
            joints: vec!["w2".into()],
            ..Default::default()
        }]
    });
    assert_eq!(err.key(), Some("sensors.faults[0].joints[0]"));
    // A disabled spring is not checked against the model (it is never built).
    let mut cfg = PlantConfig::default();
    cfg.spring.joint = "nothing".into();
    Plant::new(&baxter(), &cfg).unwrap();
}
