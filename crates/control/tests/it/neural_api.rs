//! Configuration, dynamic-node hooks (docs/method.md section 4) and observers.

use crate::common;
use admittance_control::*;
use common::*;

fn key_of(cfg: &NeuralControllerConfig) -> String {
    NeuralController::new(two_link(), cfg)
        .map(|_| ())
        .expect_err("invalid")
        .key
}

#[test]
fn invalid_configurations_name_the_key() {
    let d = NeuralControllerConfig::default;
    let lumped = |network: NetworkConfig| FNetworkConfig::Lumped {
        include_e2: false,
        network,
    };
    let net = NetworkConfig::default;
    let cases: Vec<(NeuralControllerConfig, &str)> = vec![
        (
            NeuralControllerConfig {
                k1: (-12.0).into(),
                ..d()
            },
            "k1",
        ),
        (
            NeuralControllerConfig {
                k2: vec![6.0, 6.0, 6.0].into(),
                ..d()
            },
            "k2",
        ),
        (
            NeuralControllerConfig {
                k2: vec![6.0, f64::NAN].into(),
                ..d()
            },
            "k2[1]",
        ),
        (
            NeuralControllerConfig {
                f: lumped(NetworkConfig {
                    width: Some(-1.0),
                    ..net()
                }),
                ..d()
            },
            "f.network.width",
        ),
        (
            NeuralControllerConfig {
                f: lumped(NetworkConfig {
                    theta: Some(0.0),
                    ..net()
                }),
                ..d()
            },
            "f.network.theta",
        ),
        (
            NeuralControllerConfig {
                f: lumped(NetworkConfig {
                    sigma: -0.1,
                    ..net()
                }),
                ..d()
            },
            "f.network.sigma",
        ),
        (
            NeuralControllerConfig {
                f: lumped(NetworkConfig {
                    ranges: Some(vec![[-1.0, 1.0]; 3]),
                    ..net()
                }),
                ..d()
            },
            "f.network.ranges",
        ),
        (
            NeuralControllerConfig {
                f: lumped(NetworkConfig {
                    ranges: Some(vec![[1.0, -1.0]; 4]),
                    ..net()
                }),
                ..d()
            },
            "f.network.ranges[0]",
        ),
        (
            NeuralControllerConfig {
                f: lumped(NetworkConfig {
                    capacity: Some(100),
                    ..net()
                }),
                ..d()
            },
            "f.network.capacity",
        ),
        (
            NeuralControllerConfig {
                f: lumped(NetworkConfig {
                    placement: Placement::Lattice { points: vec![2; 3] },
                    ..net()
                }),
                ..d()
            },
            "f.network.placement.points",
        ),
        (
            NeuralControllerConfig {
                f: lumped(NetworkConfig {
                    lower: Some(vec![0.0; 8]),
                    ..net()
                }),
                ..d()
            },
            "f.network.upper",
        ),
        (
            NeuralControllerConfig {
                f: lumped(NetworkConfig {
                    relevance_window: 0,
                    ..net()
                }),
                ..d()
            },
            "f.network.relevance_window",
        ),
        (
            NeuralControllerConfig {
                f: FNetworkConfig::Split {
                    m: net(),
                    c: NetworkConfig {
                        sigma: f64::INFINITY,
                        ..net()
                    },
                    g: net(),
                },
                ..d()
            },
            "f.c.sigma",
        ),
        (
            NeuralControllerConfig {
                deadzone_network: NetworkConfig {
                    theta: Some(-0.125),
                    ..net()
                },
                ..d()
            },
            "deadzone_network.theta",
        ),
        (
            NeuralControllerConfig {
                safe_hold: SafeHoldConfig {
                    damping: (-1.0).into(),
                    ..Default::default()
                },
                ..d()
            },
            "safe_hold.damping",
        ),
        (
            NeuralControllerConfig {
                safe_hold: SafeHoldConfig {
                    effort_limits: Some(vec![1.0, 0.0].into()),
                    ..Default::default()
                },
                ..d()
            },
            "safe_hold.effort_limits[1]",
        ),
    ];
    for (cfg, key) in cases {
        assert_eq!(key_of(&cfg), key);
    }
    // A disabled deadzone network is not validated.
    let cfg = NeuralControllerConfig {
        deadzone_compensation: false,
        deadzone_network: NetworkConfig {
            theta: Some(-1.0),
            ..net()
        },
        ..d()
    };
    assert!(NeuralController::new(two_link(), &cfg).is_ok());
}

#[test]
fn configuration_is_serde_with_defaults_and_rejects_unknown_keys() {
    let cfg: NeuralControllerConfig = serde_json::from_str("{}").unwrap();
    assert_eq!(cfg, NeuralControllerConfig::default());
    let text = r#"{
        "k1": [12, 10], "k2": 6,
        "f": {"form": "lumped", "include_e2": true,
              "network": {"placement": {"kind": "random", "count": 64, "seed": 9}, "theta": 0.03, "width": 2.5}},
        "deadzone_compensation": false,
        "safe_hold": {"damping": 1.0, "stale_steps": 20}
    }"#;
    let cfg: NeuralControllerConfig = serde_json::from_str(text).unwrap();
    let c = NeuralController::new(two_link(), &cfg).unwrap();
    assert_eq!(c.k1(), &[12.0, 10.0]);
    let f = c.network(NetworkId::F).unwrap();
    assert_eq!((f.len(), f.input_dim(), f.capacity()), (64, 10, 64 + 128));
    assert!((f.gamma() - 1.0 / 0.03).abs() < 1e-9 && f.sigma() == 0.035);
    assert_eq!(f.widths()[0], 2.5);
    assert!(c.network(NetworkId::Deadzone).is_none());
    let split: NeuralControllerConfig = serde_json::from_str(
        r#"{"f": {"form": "split", "m": {"placement": {"kind": "lattice", "points": [3, 3]}}}}"#,
    )
    .unwrap();
    let c = NeuralController::new(two_link(), &split).unwrap();
    assert_eq!(c.node_count(NetworkId::M), 9);
    assert_eq!(c.network(NetworkId::G).unwrap().outputs(), 2);
    // Paper's default boxes: the f box and the deadzone box.
    let c = NeuralController::new(two_link(), &NeuralControllerConfig::default()).unwrap();
    let t = c.network(NetworkId::Deadzone).unwrap();
    assert!(t.centres().chunks(8).all(|u| u[0].abs() <= 10.0
        && u[2].abs() <= 1.3
        && u[4].abs() <= 1.5
        && u[6].abs() <= 1.0));
    assert!(t.centres().chunks(8).any(|u| u[0].abs() > 5.0));
    for bad in [
        r#"{"k3": 1}"#,
        r#"{"f": {"form": "lumped", "network": {"widht": 1.0}}}"#,
        r#"{"f": {"form": "lumped", "extra": 1}}"#,
        r#"{"f": {"form": "tree"}}"#,
        r#"{"deadzone_network": {"growth": {"neighbours": 3, "distance_threshold": 1.0, "spacing": 0.1}}}"#,
        r#"{"safe_hold": {"dampin": 1}}"#,
    ] {
        assert!(
            serde_json::from_str::<NeuralControllerConfig>(bad).is_err(),
            "{bad}"
        );
    }
    let err = serde_json::from_str::<NeuralControllerConfig>(
        r#"{"f": {"form": "lumped", "network": {"widht": 1.0}}}"#,
    )
    .unwrap_err();
    assert!(err.to_string().contains("widht"), "{err}");
    let err = serde_json::from_str::<PdConfig>(r#"{"kp": 1, "kd": 1, "ki": 1}"#).unwrap_err();
    assert!(err.to_string().contains("ki"));
}

fn narrow() -> NeuralControllerConfig {
    // Narrow nodes (the default width for this box is about 3.1) so that many stay
    // irrelevant along the trajectory, and a relevance window (7 s) longer than the
    // trajectory's period.
    let network = NetworkConfig {
        width: Some(1.25),
        relevance_window: 7000,
        capacity: Some(600),
        ..NetworkConfig::default()
    };
    NeuralControllerConfig {
        f: FNetworkConfig::Lumped {
            include_e2: false,
            network,
        },
        deadzone_compensation: false,
        ..Default::default()
    }
}

#[test]
fn discard_removes_irrelevant_nodes_and_keeps_tracking() {
    let model = two_link();
    let mut c = NeuralController::new(model.clone(), &narrow()).unwrap();
    simulate(&mut c, &model, &sine, &SimOptions::new(2, 10.0), |_, _| {});
    let before = c.node_count(NetworkId::F);
    // f_hat along the trajectory, before and after the discard, with the weights frozen.
    c.set_adaptation(false);
    let mut probe = c.clone();
    let mut fa = Vec::new();
    let la = simulate(
        &mut probe,
        &model,
        &sine,
        &SimOptions::new(2, 4.0),
        |_, c| fa.push(c.f_hat()[0]),
    );
    let removed = c.discard(NetworkId::F, 0.05);
    assert!(
        removed > 0 && removed < before,
        "removed {removed} of {before}"
    );
    assert_eq!(c.node_count(NetworkId::F), before - removed);
    let mut fb = Vec::new();
    let lb = simulate(
        &mut c.clone(),
        &model,
        &sine,
        &SimOptions::new(2, 4.0),
        |_, c| fb.push(c.f_hat()[0]),
    );
    let rms = |v: &mut dyn Iterator<Item = f64>| {
        let (s, k) = v.fold((0.0, 0usize), |(s, k), x| (s + x * x, k + 1));
        (s / k as f64).sqrt()
    };
    let diff = rms(&mut fa.iter().zip(&fb).map(|(a, b)| a - b));
    let scale = rms(&mut fa.iter().copied());
    // And with adaptation on after the discard (as the paper continues learning).
    c.set_adaptation(true);
    let lc = simulate(&mut c, &model, &sine, &SimOptions::new(2, 4.0), |_, _| {});
    eprintln!(
        "discarded {removed} of {before}; rms f_hat change {diff:.3e} (rms f_hat {scale:.3}); tracking rms {:.2e} -> frozen {:.2e}, adapting {:.2e}",
        la.rms(0, 1.0, 4.0), lb.rms(0, 1.0, 4.0), lc.rms(0, 1.0, 4.0)
    );
    assert!(
        removed > before / 5,
        "a good share of the nodes is irrelevant"
    );
    assert!(
        diff < 0.1 * scale,
        "irrelevant nodes carry little: {diff} vs {scale}"
    );
    assert!(lc.rms(0, 1.0, 4.0) < 2.0 * la.rms(0, 1.0, 4.0) + 1e-4);
    assert_eq!(c.discard(NetworkId::Deadzone, 0.05), 0, "absent network");
}

#[test]
fn growth_adds_nodes_near_the_trajectory() {
    let model = two_link();
    let mut c = NeuralController::new(model.clone(), &narrow()).unwrap();
    let before = c.node_count(NetworkId::F);
    let request = GrowthRequest {
        nodes: 20,
        interval_steps: 25,
        params: GrowthParams::new(4, 0.5, 0.2),
    };
    c.request_growth(NetworkId::F, request).unwrap();
    assert_eq!(c.growth_progress(NetworkId::F).pending, 20);
    simulate(&mut c, &model, &sine, &SimOptions::new(2, 5.0), |_, _| {});
    let p = c.growth_progress(NetworkId::F);
    assert_eq!((p.added, p.pending), (20, 0), "{p:?}");
    assert_eq!(c.node_count(NetworkId::F), before + 20);
    // The new centres lie on the trajectory's inputs (q within the motion's range).
    let layer = c.network(NetworkId::F).unwrap();
    for i in before..before + 20 {
        let u = layer.centre(i).unwrap();
        assert!(
            u[0].abs() <= 0.51 && (u[1] - 0.4).abs() <= 0.31,
            "centre {u:?}"
        );
    }
    // Capacity bounds growth.
    let mut cfg = narrow();
    if let FNetworkConfig::Lumped { network, .. } = &mut cfg.f {
        network.capacity = Some(515);
    }
    let mut c = NeuralController::new(model.clone(), &cfg).unwrap();
    c.request_growth(
        NetworkId::F,
        GrowthRequest {
            nodes: 20,
            interval_steps: 1,
            params: GrowthParams::new(4, 0.0, 0.0),
        },
    )
    .unwrap();
    simulate(&mut c, &model, &sine, &SimOptions::new(2, 1.0), |_, _| {});
    assert_eq!(c.node_count(NetworkId::F), 515);
    assert_eq!(c.growth_progress(NetworkId::F).pending, 0);
    // Errors.
    assert!(c.request_growth(NetworkId::M, request).is_err());
    assert_eq!(
        c.request_growth(
            NetworkId::F,
            GrowthRequest {
                interval_steps: 0,
                ..request
            }
        )
        .unwrap_err()
        .key,
        "growth.interval_steps"
    );
    // Reset restores the initial network.
    c.reset();
    assert_eq!(c.node_count(NetworkId::F), 512);
}

#[test]
fn predict_f_matches_the_step_output() {
    let model = two_link();
    for cfg in [
        NeuralControllerConfig::default(),
        NeuralControllerConfig {
            f: FNetworkConfig::Split {
                m: NetworkConfig::default(),
                c: NetworkConfig::default(),
                g: NetworkConfig::default(),
            },
            ..Default::default()
        },
    ] {
        let mut c = NeuralController::new(model.clone(), &cfg).unwrap();
        simulate(&mut c, &model, &sine, &SimOptions::new(2, 2.0), |_, _| {});
        c.set_adaptation(false);
        let (q, v, mut a) = ([0.1, 0.3], [0.2, -0.1], [0.0; 2]);
        let input = ControlInput {
            time: 0.0,
            q: &q,
            qdot: &v,
            q_ref: &[0.15, 0.25],
            qdot_ref: &[0.3, 0.0],
            qddot_ref: &[1.0, -1.0],
            external_torque_estimate: &[0.0; 2],
        };
        let mut tau = [0.0; 2];
        assert!(c.step(&input, 1e-3, &mut tau).is_ok());
        let (alpha, alpha_dot, e2) = (c.alpha().to_vec(), c.alpha_dot().to_vec(), c.e2().to_vec());
        c.predict_f(&q, &v, &alpha, &alpha_dot, &e2, &mut a)
            .unwrap();
        for j in 0..2 {
            assert!(
                (a[j] - c.f_hat()[j]).abs() < 1e-12 * (1.0 + a[j].abs()),
                "{a:?} vs {:?}",
                c.f_hat()
            );
        }
        // The law: tau = f_hat + K2 e2 + Dtau_hat - tau_ext_hat (unclamped here).
        for j in 0..2 {
            let expect = c.f_hat()[j] + 6.0 * e2[j] + c.deadzone_estimate()[j];
            assert!((tau[j] - expect).abs() < 1e-12);
        }
        assert!(c
            .predict_f(&q, &v, &alpha, &alpha_dot, &e2, &mut [0.0; 3])
            .is_err());
    }
}

#[test]
fn law_signs_on_a_single_step() {
    // Zero weights: tau = K2 e2 - tau_ext_hat, e2 = q_r' - q' + K1 (q_r - q).
    let model = two_link();
    let mut c = NeuralController::new(
        model,
        &NeuralControllerConfig {
            adaptation: false,
            ..Default::default()
        },
    )
    .unwrap();
    let input = ControlInput {
        time: 0.0,
        q: &[0.0, 0.0],
        qdot: &[0.0, 0.1],
        q_ref: &[0.01, 0.0],
        qdot_ref: &[0.0, 0.0],
        qddot_ref: &[0.0, 0.0],
        external_torque_estimate: &[0.5, -0.5],
    };
    let mut tau = [0.0; 2];
    assert!(c.step(&input, 1e-3, &mut tau).is_ok());
    assert!((c.e1()[0] - 0.01).abs() < 1e-15);
    assert!((c.e2()[0] - 0.12).abs() < 1e-12 && (c.e2()[1] + 0.1).abs() < 1e-12);
    assert!(
        (c.alpha_dot()[1] + 1.2).abs() < 1e-12,
        "alpha' = q_r'' + K1 (q_r' - q')"
    );
    assert!((tau[0] - (6.0 * 0.12 - 0.5)).abs() < 1e-12);
    assert!((tau[1] - (6.0 * -0.1 + 0.5)).abs() < 1e-12);
}

#[test]
fn observers() {
    let input = ObserverInput {
        time: 0.0,
        q: &[0.0; 2],
        qdot: &[0.0; 2],
        qddot: &[0.0; 2],
        tau_commanded: &[0.0; 2],
    };
    let mut est = [9.0; 2];
    let mut none = NoObserver::new(2);
    assert!(none.update(&input, 1e-3, &mut est).is_ok());
    assert_eq!(est, [0.0; 2]);
    let mut oracle = OracleObserver::new(2);
    oracle.set_true_value(&[0.3, -0.2]);
    assert!(oracle.update(&input, 1e-3, &mut est).is_ok());
    assert_eq!(est, [0.3, -0.2]);
    oracle.set_true_value(&[f64::NAN, 0.0]);
    assert_eq!(
        oracle.update(&input, 1e-3, &mut est).fault(),
        Some(Fault::NonFiniteEstimate { joint: 0 })
    );
    assert_eq!(est, [0.0; 2]);
    assert!(!oracle.update(&input, 1e-3, &mut [0.0; 3]).is_ok());
    let boxed: Vec<Box<dyn Observer>> = vec![Box::new(none), Box::new(oracle)];
    assert_eq!(
        boxed.iter().map(|o| o.name()).collect::<Vec<_>>(),
        ["none", "oracle"]
    );
}
