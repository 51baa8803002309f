//! The admittance model and the reference saturation (docs/method.md section 2, eq. 5-7).

use admittance_control::*;
use proptest::prelude::*;

const RHO: f64 = 0.95;
const C: f64 = 1.1;

fn one_joint(saturation: Option<SaturationConfig>) -> Admittance {
    let cfg = AdmittanceConfig {
        damping: 3.0.into(),
        stiffness: 5.0.into(),
        inertia: None,
        saturation,
    };
    Admittance::new(1, &cfg).unwrap()
}

fn paper_sat() -> SaturationConfig {
    SaturationConfig {
        rho: RHO,
        centre: 0.0.into(),
        half_range: C.into(),
    }
}

#[test]
fn saturation_is_continuous_and_once_differentiable_at_the_knees() {
    let knee = RHO * C;
    let h = 1e-7;
    for k in [knee, -knee] {
        let (below, d_below, _) = saturate(k - h, RHO, C);
        let (at, d_at, _) = saturate(k, RHO, C);
        let (above, d_above, _) = saturate(k + h, RHO, C);
        assert!((at - k).abs() < 1e-15, "sat(knee) = knee");
        assert!(
            (above - below - 2.0 * h).abs() < 1e-12,
            "continuous with slope 1 across the knee"
        );
        assert!(
            (d_below - 1.0).abs() < 1e-5 && (d_above - 1.0).abs() < 1e-5 && d_at == 1.0,
            "sat' = 1 on both sides"
        );
        // The analytic derivative matches a central difference on each side.
        for y in [k - 10.0 * h, k + 10.0 * h] {
            let fd = (saturate(y + h, RHO, C).0 - saturate(y - h, RHO, C).0) / (2.0 * h);
            assert!((fd - saturate(y, RHO, C).1).abs() < 1e-6);
        }
    }
    // sat'' matches a finite difference of sat' away from the knees.
    for y in [1.06, 1.2, -1.07, -1.5] {
        let fd = (saturate(y + h, RHO, C).1 - saturate(y - h, RHO, C).1) / (2.0 * h);
        assert!((fd - saturate(y, RHO, C).2).abs() < 1e-5, "sat'' at {y}");
    }
}

#[test]
fn paper_values_give_gamma_0_055() {
    // gamma = (1 - rho) C; the paper quotes 0.05 for rho = 0.95, C = 1.1 (0.055 exactly).
    let knee = RHO * C;
    let gamma = (1.0 - RHO) * C;
    let (s, ds, dds) = saturate(knee + gamma, RHO, C);
    let e = (-1.0f64).exp();
    assert!((s - (gamma * (1.0 - e) + knee)).abs() < 1e-15);
    assert!((ds - e).abs() < 1e-15 && (dds + e / gamma).abs() < 1e-12);
}

proptest! {
    #[test]
    fn saturation_is_strictly_increasing(a in -2.1f64..2.1, delta in 1e-6f64..1.0) {
        // Where floating point resolves the difference: |y| - rho C up to ~20 gamma (beyond,
        // sat(y) is within an ulp of C; `saturation_is_monotone_everywhere` covers that).
        let b = a + delta;
        let (sa, da, _) = saturate(a, RHO, C);
        let (sb, _, _) = saturate(b, RHO, C);
        prop_assert!(da > 0.0);
        prop_assert!(sb > sa, "sat({b}) = {sb} <= sat({a}) = {sa}");
    }

    #[test]
    fn saturation_is_monotone_everywhere(a in -1e12f64..1e12, b in -1e12f64..1e12) {
        let sat = Saturation::new(1, &paper_sat()).unwrap();
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        prop_assert!(sat.apply(0, lo).0 <= sat.apply(0, hi).0);
    }

    #[test]
    fn reference_strictly_inside_for_huge_inputs(y in prop_oneof![-1e300f64..1e300, -1e6f64..1e6, -50.0f64..50.0],
                                                 centre in -2.0f64..2.0, half in 0.01f64..3.0) {
        let cfg = SaturationConfig { rho: RHO, centre: centre.into(), half_range: half.into() };
        let sat = Saturation::new(1, &cfg).unwrap();
        let (r, d, _) = sat.apply(0, y);
        prop_assert!(r > centre - half && r < centre + half, "q_r = {r} not inside ({}, {})", centre - half, centre + half);
        prop_assert!((0.0..=1.0).contains(&d));
    }

    #[test]
    fn zero_estimate_keeps_the_desired_trajectory(t0 in 0.0f64..10.0, amp in 0.0f64..1.0) {
        let mut adm = one_joint(Some(paper_sat()));
        for k in 0..200 {
            let t = t0 + k as f64 * 1e-3;
            let q_d = [amp * t.sin()];
            let v_d = [amp * t.cos()];
            let a_d = [-amp * t.sin()];
            let st = adm.step(&AdmittanceInput { q_d: &q_d, qdot_d: &v_d, qddot_d: &a_d, external_torque_estimate: &[0.0] }, 1e-3);
            prop_assert!(st.is_ok());
            // amp < rho C: inside the linear zone, so q_r == q_d exactly.
            prop_assert_eq!(adm.q_r()[0], q_d[0]);
            prop_assert_eq!(adm.qdot_r()[0], v_d[0]);
            prop_assert_eq!(adm.qddot_r()[0], a_d[0]);
        }
    }
}

#[test]
fn yields_in_the_direction_of_the_external_torque_and_settles_at_g_d_inverse() {
    for (inertia, tau) in [
        (None, 2.0),
        (None, -1.5),
        (Some(0.2), 2.0),
        (Some(0.2), -1.5),
    ] {
        let cfg = AdmittanceConfig {
            damping: 3.0.into(),
            stiffness: 5.0.into(),
            inertia: inertia.map(JointValues::from),
            saturation: None,
        };
        let mut adm = Admittance::new(2, &cfg).unwrap();
        let q_d = [0.3, -0.2];
        let zero = [0.0; 2];
        let est = [tau, 0.0];
        let mut prev = 0.0f64;
        for k in 0..20_000 {
            assert!(adm
                .step(
                    &AdmittanceInput {
                        q_d: &q_d,
                        qdot_d: &zero,
                        qddot_d: &zero,
                        external_torque_estimate: &est
                    },
                    1e-3
                )
                .is_ok());
            let dev = adm.q_r()[0] - q_d[0];
            if k < 300 {
                assert!(
                    dev * tau > 0.0,
                    "yields along tau_ext_hat (inertia {inertia:?}, step {k})"
                );
                if inertia.is_none() {
                    assert!(
                        dev.abs() > prev.abs(),
                        "first-order model moves monotonically towards the steady state"
                    );
                }
            }
            prev = dev;
            assert_eq!(adm.q_r()[1], q_d[1], "an unloaded joint stays on q_d");
        }
        let expect = tau / 5.0;
        assert!(
            (adm.deviation()[0] - expect).abs() < 1e-9,
            "steady state q_a - q_d = G_d^-1 tau ({inertia:?})"
        );
        assert!(adm.qdot_r()[0].abs() < 1e-9);
    }
}

#[test]
fn saturated_reference_derivatives_follow_the_chain_rule() {
    let mut adm = one_joint(Some(paper_sat()));
    let dt = 1e-4;
    let mut prev: Option<(f64, f64, f64, f64)> = None;
    let knee = RHO * C;
    for k in 0..40_000 {
        let t = k as f64 * dt;
        let q_d = [1.5 * t.sin()];
        let v_d = [1.5 * t.cos()];
        let a_d = [-1.5 * t.sin()];
        assert!(adm
            .step(
                &AdmittanceInput {
                    q_d: &q_d,
                    qdot_d: &v_d,
                    qddot_d: &a_d,
                    external_torque_estimate: &[0.7]
                },
                dt
            )
            .is_ok());
        let (r, rd, rdd, qa) = (
            adm.q_r()[0],
            adm.qdot_r()[0],
            adm.qddot_r()[0],
            adm.q_a()[0],
        );
        assert!(r.abs() < C);
        if let Some((pr, prd, prdd, pqa)) = prev {
            // Finite differences agree with the reported derivatives (trapezoidal rule). q_r
            // is only once differentiable: q_r'' jumps where q_a crosses a knee.
            let crossed = (qa.abs() > knee) != (pqa.abs() > knee);
            let tol = if crossed { 5e-3 } else { 1e-4 };
            assert!(
                ((r - pr) / dt - 0.5 * (rd + prd)).abs() < tol,
                "q_r' at t = {t}"
            );
            if !crossed {
                assert!(
                    ((rd - prd) / dt - 0.5 * (rdd + prdd)).abs() < 0.02,
                    "q_r'' at t = {t}"
                );
            }
        }
        prev = Some((r, rd, rdd, qa));
    }
}

#[test]
fn asymmetric_limits_use_centre_and_half_range() {
    let sat = SaturationConfig::from_limits(0.9, &[-0.5], &[2.5]);
    let s = Saturation::new(1, &sat).unwrap();
    assert_eq!(s.centre(), &[1.0]);
    assert_eq!(s.half_range(), &[1.5]);
    assert_eq!(
        s.apply(0, 1.7).0,
        1.7,
        "inside the linear zone [1 - 1.35, 1 + 1.35]"
    );
    assert!(s.apply(0, 1e9).0 < 2.5 && s.apply(0, 1e9).0 > 2.49);
    assert!(s.apply(0, -1e9).0 > -0.5 && s.apply(0, -1e9).0 < -0.49);
    // An infinite half range disables the joint's saturation.
    let free = SaturationConfig {
        rho: 0.9,
        centre: 0.0.into(),
        half_range: vec![1.0, f64::INFINITY].into(),
    };
    let s = Saturation::new(2, &free).unwrap();
    assert_eq!(s.apply(1, 123.0), (123.0, 1.0, 0.0));
}

#[test]
fn invalid_configurations_name_the_key() {
    let base = AdmittanceConfig::paper();
    let cases: Vec<(AdmittanceConfig, &str)> = vec![
        (
            AdmittanceConfig {
                damping: 0.0.into(),
                ..base.clone()
            },
            "damping",
        ),
        (
            AdmittanceConfig {
                damping: vec![3.0, -1.0].into(),
                ..base.clone()
            },
            "damping[1]",
        ),
        (
            AdmittanceConfig {
                stiffness: f64::NAN.into(),
                ..base.clone()
            },
            "stiffness",
        ),
        (
            AdmittanceConfig {
                stiffness: vec![1.0, 2.0, 3.0].into(),
                ..base.clone()
            },
            "stiffness",
        ),
        (
            AdmittanceConfig {
                inertia: Some((-0.1).into()),
                ..base.clone()
            },
            "inertia",
        ),
        (
            AdmittanceConfig {
                saturation: Some(SaturationConfig {
                    rho: 1.0,
                    ..paper_sat()
                }),
                ..base.clone()
            },
            "saturation.rho",
        ),
        (
            AdmittanceConfig {
                saturation: Some(SaturationConfig {
                    rho: 0.0,
                    ..paper_sat()
                }),
                ..base.clone()
            },
            "saturation.rho",
        ),
        (
            AdmittanceConfig {
                saturation: Some(SaturationConfig {
                    half_range: 0.0.into(),
                    ..paper_sat()
                }),
                ..base.clone()
            },
            "saturation.half_range",
        ),
        (
            AdmittanceConfig {
                saturation: Some(SaturationConfig {
                    half_range: vec![1.0, -2.0].into(),
                    ..paper_sat()
                }),
                ..base.clone()
            },
            "saturation.half_range[1]",
        ),
        (
            AdmittanceConfig {
                saturation: Some(SaturationConfig {
                    centre: f64::INFINITY.into(),
                    ..paper_sat()
                }),
                ..base.clone()
            },
            "saturation.centre",
        ),
    ];
    for (cfg, key) in cases {
        let err = Admittance::new(2, &cfg).expect_err(key);
        assert_eq!(err.key, key, "{err}");
        assert!(err.to_string().contains(key));
    }
    assert!(Admittance::new(2, &base).is_ok());
}

#[test]
fn configuration_rejects_unknown_keys() {
    let ok = r#"{"damping": 3.0, "stiffness": [5.0, 5.0], "saturation": {"rho": 0.95, "half_range": 1.1}}"#;
    let cfg: AdmittanceConfig = serde_json::from_str(ok).unwrap();
    assert!(Admittance::new(2, &cfg).is_ok());
    let bad = r#"{"damping": 3.0, "stiffness": 5.0, "stifness": 5.0}"#;
    let err = serde_json::from_str::<AdmittanceConfig>(bad)
        .unwrap_err()
        .to_string();
    assert!(err.contains("stifness"), "{err}");
    let bad = r#"{"damping": 3.0, "stiffness": 5.0, "saturation": {"rho": 0.9, "half_range": 1.0, "gamma": 0.1}}"#;
    assert!(serde_json::from_str::<AdmittanceConfig>(bad)
        .unwrap_err()
        .to_string()
        .contains("gamma"));
}

#[test]
fn faults_freeze_the_state_and_hold_the_reference() {
    let mut adm = one_joint(Some(paper_sat()));
    let st = adm.step(
        &AdmittanceInput {
            q_d: &[0.2],
            qdot_d: &[0.1],
            qddot_d: &[0.0],
            external_torque_estimate: &[1.0],
        },
        1e-3,
    );
    assert!(st.is_ok());
    let (r, dev) = (adm.q_r()[0], adm.deviation()[0]);
    for bad in [
        AdmittanceInput {
            q_d: &[f64::NAN],
            qdot_d: &[0.1],
            qddot_d: &[0.0],
            external_torque_estimate: &[1.0],
        },
        AdmittanceInput {
            q_d: &[0.2],
            qdot_d: &[0.1],
            qddot_d: &[f64::INFINITY],
            external_torque_estimate: &[1.0],
        },
        AdmittanceInput {
            q_d: &[0.2],
            qdot_d: &[0.1],
            qddot_d: &[0.0],
            external_torque_estimate: &[f64::NAN],
        },
        AdmittanceInput {
            q_d: &[0.2, 0.0],
            qdot_d: &[0.1],
            qddot_d: &[0.0],
            external_torque_estimate: &[1.0],
        },
    ] {
        assert!(!adm.step(&bad, 1e-3).is_ok());
        assert_eq!(adm.q_r()[0], r);
        assert_eq!(adm.qdot_r()[0], 0.0);
        assert_eq!(adm.deviation()[0], dev);
    }
    assert_eq!(
        adm.step(
            &AdmittanceInput {
                q_d: &[0.2],
                qdot_d: &[0.1],
                qddot_d: &[0.0],
                external_torque_estimate: &[1.0]
            },
            f64::NAN
        )
        .fault(),
        Some(Fault::InvalidTimeStep)
    );
    assert!(adm
        .step(
            &AdmittanceInput {
                q_d: &[0.2],
                qdot_d: &[0.1],
                qddot_d: &[0.0],
                external_torque_estimate: &[1.0]
            },
            1e-3
        )
        .is_ok());
    assert!(adm.deviation()[0] > dev, "resumes");
}

/// A joint without two finite limits (continuous, or one-sided) is not saturated: centre 0,
/// half range infinite, never a NaN centre (the Python `Admittance(bound=None)` uses this).
#[test]
fn joints_without_finite_limits_are_not_saturated() {
    let inf = f64::INFINITY;
    let sat = SaturationConfig::from_limits(0.95, &[-1.0, -inf, -inf], &[1.0, 2.0, inf]);
    let s = Saturation::new(3, &sat).unwrap();
    assert_eq!(s.centre(), &[0.0, 0.0, 0.0]);
    assert_eq!(s.half_range(), &[1.0, inf, inf]);
    assert_eq!(s.apply(1, 50.0).0, 50.0);
    assert_eq!(s.apply(2, -50.0).0, -50.0);
}
