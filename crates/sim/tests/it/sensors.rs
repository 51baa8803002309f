//! Encoders and filtered differentiation: quantisation, seeded noise, delays of the
//! filter, the derivative of a ramp, and injected faults.

use crate::common;
use admittance_loop::Measurement;
use admittance_sim::*;
use common::*;

fn sensors(cfg: SensorConfig, rate: f64) -> Sensors {
    Sensors::new(&one_joint(1e-3), &cfg, rate).unwrap()
}

#[test]
fn encoder_quantises_to_its_resolution() {
    let mut s = sensors(
        SensorConfig {
            counts_per_rev: 4096.0,
            filter_cutoff_hz: 0.0,
            ..Default::default()
        },
        1000.0,
    );
    let res = std::f64::consts::TAU / 4096.0;
    for k in 0..100 {
        let q = 0.0123 * k as f64;
        let m = s.sample(k as f64 * 1e-3, &[q], &[0.0]).unwrap();
        let counts = m.q[0] / res;
        assert!((counts - counts.round()).abs() < 1e-9 && (m.q[0] - q).abs() <= 0.5 * res + 1e-15);
    }
}

#[test]
fn noise_is_gaussian_with_the_configured_deviation_and_seeded() {
    let cfg = SensorConfig {
        noise_std: 1e-3,
        seed: 42,
        filter_cutoff_hz: 0.0,
        ..Default::default()
    };
    let mut s = sensors(cfg.clone(), 1000.0);
    let samples: Vec<f64> = (0..20_000)
        .map(|k| s.sample(k as f64 * 1e-3, &[0.5], &[0.0]).unwrap().q[0] - 0.5)
        .collect();
    let mean = samples.iter().sum::<f64>() / samples.len() as f64;
    let std =
        (samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / samples.len() as f64).sqrt();
    assert!(
        mean.abs() < 3e-5 && (std / 1e-3 - 1.0).abs() < 0.03,
        "mean {mean}, std {std}"
    );
    let mut again = sensors(cfg, 1000.0);
    for (k, x) in samples.iter().take(100).enumerate() {
        assert_eq!(
            (again.sample(k as f64 * 1e-3, &[0.5], &[0.0]).unwrap().q[0] - 0.5).to_bits(),
            x.to_bits()
        );
    }
    again.reset();
    assert_eq!(
        (again.sample(0.0, &[0.5], &[0.0]).unwrap().q[0] - 0.5).to_bits(),
        samples[0].to_bits()
    );
}

/// A ramp `q = 0.5 t`: after the filter settles the velocity is the slope and the
/// acceleration zero; the filtered angle lags by the filter's group delay, and the torque
/// passes through the same filter (same delay).
#[test]
fn differentiation_of_a_ramp_and_matching_delays() {
    let fs = 1000.0;
    let mut s = sensors(
        SensorConfig {
            filter_cutoff_hz: 20.0,
            ..Default::default()
        },
        fs,
    );
    let delay = s.filter().dc_group_delay();
    assert!(delay > 5.0 && delay < 20.0, "{delay} samples");
    let mut last = None;
    for k in 0..2000 {
        let t = k as f64 / fs;
        last = Some(s.sample(t, &[0.5 * t], &[3.0 * t]).unwrap().clone());
    }
    let m = last.unwrap();
    assert!((m.qdot[0] - 0.5).abs() < 1e-9, "{}", m.qdot[0]);
    assert!(m.qddot[0].abs() < 1e-6, "{}", m.qddot[0]);
    let lag_q = (0.5 * m.time - m.q_filtered[0]) / 0.5 * fs;
    let lag_tau = (3.0 * m.time - m.tau_filtered[0]) / 3.0 * fs;
    assert!(
        (lag_q - delay).abs() < 1e-6 && (lag_tau - delay).abs() < 1e-6,
        "{lag_q} {lag_tau} {delay}"
    );
}

#[test]
fn a_nan_sample_is_passed_on_raw_but_the_derived_signals_hold() {
    let cfg = SensorConfig {
        faults: vec![FaultConfig {
            kind: FaultKind::Nan,
            joints: vec![],
            t_start: 0.05,
            t_end: 0.0515,
            value: None,
        }],
        ..Default::default()
    };
    let mut s = sensors(cfg, 1000.0);
    let mut before = None;
    for k in 0..100 {
        let t = k as f64 * 1e-3;
        let m = s.sample(t, &[(3.0 * t).sin()], &[1.0]).unwrap().clone();
        if k == 49 {
            before = Some(m.clone());
        }
        if k == 50 || k == 51 {
            let b = before.as_ref().unwrap();
            assert!(m.q[0].is_nan() && m.injected_nan[0] && !m.is_finite());
            assert_eq!(
                (m.q_filtered[0], m.qdot[0], m.qddot[0]),
                (b.q_filtered[0], b.qdot[0], b.qddot[0])
            );
            assert!(m.tau_filtered[0].is_finite());
        } else {
            assert!(m.is_finite() && !m.injected_nan[0], "sample {k}");
        }
    }
}

#[test]
fn a_stale_sample_repeats_the_previous_value_with_its_old_timestamp() {
    let cfg = SensorConfig {
        noise_std: 1e-4,
        seed: 1,
        faults: vec![FaultConfig {
            kind: FaultKind::Stale,
            joints: vec!["j".into()],
            t_start: 0.0095,
            t_end: 0.0125,
            value: None,
        }],
        ..Default::default()
    };
    let mut s = sensors(cfg, 1000.0);
    let mut prev = None;
    for k in 0..20 {
        let t = k as f64 * 1e-3;
        let m = s.sample(t, &[t], &[0.0]).unwrap().clone();
        if (10..=12).contains(&k) {
            let p: &Measurement = prev.as_ref().unwrap();
            assert!(m.injected_stale[0]);
            assert_eq!(m.q[0], p.q[0]);
            assert_eq!(m.sample_time[0], 9.0 * 1e-3);
            assert!(m.sample_time[0] < m.time);
        } else {
            assert!(!m.injected_stale[0] && m.sample_time[0] == t);
        }
        prev = Some(m);
    }
}

#[test]
fn sensors_reject_a_bad_length() {
    let mut s = sensors(SensorConfig::default(), 1000.0);
    assert!(matches!(
        s.sample(0.0, &[0.0, 1.0], &[0.0]),
        Err(SimError::Dimension(_))
    ));
}

#[test]
fn a_spike_delivers_its_absurd_reading_once_and_a_screen_can_refuse_it() {
    let cfg = SensorConfig {
        faults: vec![
            FaultConfig {
                kind: FaultKind::AngleSpike,
                t_start: 0.0195,
                t_end: 0.0205,
                ..Default::default()
            },
            FaultConfig {
                kind: FaultKind::TorqueSpike,
                t_start: 0.0295,
                t_end: 0.0305,
                value: Some(1e300),
                ..Default::default()
            },
        ],
        ..Default::default()
    };
    let mut plain = sensors(cfg.clone(), 1000.0);
    let mut screened = sensors(cfg, 1000.0);
    for k in 0..40 {
        let t = k as f64 * 1e-3;
        let m = plain.sample(t, &[0.1], &[2.0]).unwrap();
        assert_eq!(m.q[0], if k == 20 { DEFAULT_SPIKE_VALUE } else { 0.1 });
        assert_eq!(m.tau_commanded[0], if k == 30 { 1e300 } else { 2.0 });
        let mut refused = 0;
        let m = screened
            .sample_screened(t, &[0.1], &[2.0], |_, q, tau| {
                for x in q.iter_mut().chain(tau.iter_mut()) {
                    if x.abs() > 10.0 {
                        *x = f64::NAN;
                        refused += 1;
                    }
                }
            })
            .unwrap();
        assert_eq!(refused, usize::from(k == 20 || k == 30), "sample {k}");
        // A refused value takes the NaN path: the derived signals hold.
        assert!(
            (m.q_filtered[0] - 0.1).abs() < 1e-9 && m.qdot[0].abs() < 1e-6,
            "sample {k}: {} {}",
            m.q_filtered[0],
            m.qdot[0]
        );
        assert!((m.tau_filtered[0] - 2.0).abs() < 1e-9, "sample {k}");
        assert_eq!(m.q[0].is_nan(), k == 20);
    }
}

#[test]
fn a_spike_value_is_finite_and_only_for_spikes() {
    let model = one_joint(1e-3);
    for (kind, value) in [
        (FaultKind::AngleSpike, f64::INFINITY),
        (FaultKind::TorqueSpike, f64::NAN),
        (FaultKind::Nan, 1.0),
        (FaultKind::Stale, 1.0),
    ] {
        let cfg = SensorConfig {
            faults: vec![FaultConfig {
                kind,
                value: Some(value),
                ..Default::default()
            }],
            ..Default::default()
        };
        let err = Sensors::new(&model, &cfg, 1000.0).unwrap_err();
        assert_eq!(
            err.key(),
            Some("sensors.faults[0].value"),
            "{kind:?}: {err}"
        );
    }
}
