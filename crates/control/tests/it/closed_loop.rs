//! Closed-loop checks on a 2-joint arm simulated with `aba` (docs/method.md sections 3 and 6 A):
//! the sign set of the neural controller, deadzone compensation (a quick experiment A),
//! computed torque with a perfect model, and the PD baselines.

use crate::common;
use admittance_control::*;
use common::*;

fn nn(deadzone_compensation: bool, adaptation: bool) -> NeuralController {
    let cfg = NeuralControllerConfig {
        deadzone_compensation,
        adaptation,
        ..NeuralControllerConfig::default()
    };
    NeuralController::new(two_link(), &cfg).unwrap()
}

fn assert_torques_valid(log: &SimLog, limits: &[f64]) {
    for tau in &log.torque {
        for (t, l) in tau.iter().zip(limits) {
            assert!(t.is_finite() && t.abs() <= *l, "torque {t} outside +-{l}");
        }
    }
    assert_eq!(log.faults, 0);
}

#[test]
fn nn_controller_tracks_a_sine_with_falling_error_and_bounded_weights() {
    let model = two_link();
    let mut adaptive = nn(true, true);
    let opts = SimOptions::new(2, 60.0);
    // Weight norms every second.
    let mut wf = Vec::new();
    let mut wt = Vec::new();
    let log = simulate(&mut adaptive, &model, &sine, &opts, |t, c| {
        if ((t * 1000.0).round() as u64).is_multiple_of(1000) {
            wf.push(c.weight_norm(NetworkId::F));
            wt.push(c.weight_norm(NetworkId::Deadzone));
        }
    });
    let mut frozen = nn(true, false);
    let flog = simulate(&mut frozen, &model, &sine, &opts, |_, _| {});
    let early = log.rms(0, 0.0, 1.0);
    let late = log.rms(0, 50.0, 60.0);
    let frozen_late = flog.rms(0, 50.0, 60.0);
    eprintln!("rms j0: [0,1) {early:.2e}, [50,60) {late:.2e}; frozen [50,60) {frozen_late:.2e}");
    eprintln!(
        "|W_f| at 10/30/59 s: {:.4} {:.4} {:.4}; |W_t|: {:.4} {:.4} {:.4}",
        wf[10], wf[30], wf[59], wt[10], wt[30], wt[59]
    );
    assert!(
        late < 0.5 * early,
        "error falls over time: {early:.2e} -> {late:.2e}"
    );
    assert!(
        late < 0.05 * frozen_late,
        "adaptation helps (a wrong sign would make it worse)"
    );
    assert!(log.rms(1, 50.0, 60.0) < 0.05 * flog.rms(1, 50.0, 60.0));
    for w in wf.iter().chain(&wt) {
        assert!(w.is_finite() && *w < 10.0, "weights bounded: {w}");
    }
    // sigma-modification: no drift, the second half never exceeds the first by much.
    let max = |w: &[f64]| w.iter().copied().fold(0.0, f64::max);
    assert!(
        max(&wf[30..]) < 1.5 * max(&wf[..30]) && max(&wt[30..]) < 1.5 * max(&wt[..30]),
        "weights stay bounded"
    );
    assert_torques_valid(&log, adaptive.safe_hold().effort_limits());
    assert_torques_valid(&flog, frozen.safe_hold().effort_limits());
}

#[test]
fn deadzone_network_reduces_tracking_error() {
    // A quick experiment A: a +-2 N m deadzone on joint 0.
    let model = two_link();
    let mut opts = SimOptions::new(2, 30.0);
    opts.deadzone[0] = 2.0;
    let mut comp = nn(true, true);
    let mut uncomp = nn(false, true);
    assert_eq!(uncomp.name(), "nn_uncompensated");
    assert!(uncomp.network(NetworkId::Deadzone).is_none());
    let lc = simulate(&mut comp, &model, &sine, &opts, |_, _| {});
    let lu = simulate(&mut uncomp, &model, &sine, &opts, |_, _| {});
    let (rc, ru) = (lc.rms(0, 10.0, 30.0), lu.rms(0, 10.0, 30.0));
    eprintln!("deadzone +-2 N m on joint 0: rms compensated {rc:.2e}, uncompensated {ru:.2e}");
    assert!(
        rc < ru / 3.0,
        "compensated {rc:.2e} vs uncompensated {ru:.2e}"
    );
    assert!(lc.max_abs(0, 10.0, 30.0) < lu.max_abs(0, 10.0, 30.0));
    assert!(comp.weight_norm(NetworkId::Deadzone) > 0.0);
    assert_torques_valid(&lc, comp.safe_hold().effort_limits());
    assert_torques_valid(&lu, uncomp.safe_hold().effort_limits());
}

#[test]
fn split_form_tracks_too() {
    let model = two_link();
    let small = |count| NetworkConfig {
        placement: Placement::Random { count, seed: 3 },
        ..NetworkConfig::default()
    };
    let cfg = NeuralControllerConfig {
        f: FNetworkConfig::Split {
            m: small(128),
            c: small(256),
            g: small(128),
        },
        ..NeuralControllerConfig::default()
    };
    let mut c = NeuralController::new(model.clone(), &cfg).unwrap();
    assert!(c.is_split());
    assert_eq!(c.network(NetworkId::M).unwrap().outputs(), 4);
    assert_eq!(c.network(NetworkId::C).unwrap().input_dim(), 4);
    let opts = SimOptions::new(2, 30.0);
    let log = simulate(&mut c, &model, &sine, &opts, |_, _| {});
    let mut frozen_cfg = cfg.clone();
    frozen_cfg.adaptation = false;
    let mut frozen = NeuralController::new(model.clone(), &frozen_cfg).unwrap();
    let flog = simulate(&mut frozen, &model, &sine, &opts, |_, _| {});
    let (r, rf) = (log.rms(0, 20.0, 30.0), flog.rms(0, 20.0, 30.0));
    eprintln!("split form: rms j0 adaptive {r:.2e}, frozen {rf:.2e}");
    assert!(r < 0.1 * rf);
    for id in [NetworkId::M, NetworkId::C, NetworkId::G] {
        let w = c.weight_norm(id);
        assert!(w.is_finite() && w > 0.0, "{id:?} adapted");
    }
    assert_torques_valid(&log, c.safe_hold().effort_limits());
}

#[test]
fn f_hat_approaches_the_true_lumped_function() {
    // Along the trajectory, the lumped network's output approaches
    // f = M alpha' + C alpha + G (the plant has no friction here), as experiment C measures.
    let model = two_link();
    // Without the deadzone network: its input tau_prev lets it absorb part of f.
    let mut c = nn(false, true);
    let mut data = admittance_dynamics::Data::new(&model);
    let mut f = [0.0; 2];
    let (mut early, mut late, mut norm) = ([0.0f64; 2], [0.0f64; 2], [0.0f64; 2]);
    simulate(&mut c, &model, &sine, &SimOptions::new(2, 30.0), |t, c| {
        let z = c.f_input();
        true_lumped_f(
            &model,
            &mut data,
            &z[..2],
            &z[2..4],
            c.alpha(),
            c.alpha_dot(),
            &mut f,
        )
        .unwrap();
        for j in 0..2 {
            let e2 = (c.f_hat()[j] - f[j]).powi(2);
            if t < 1.0 {
                early[j] += e2;
            } else if t >= 25.0 {
                late[j] += e2;
                norm[j] += f[j] * f[j];
            }
        }
    });
    for j in 0..2 {
        let (e, l) = ((early[j] / 1000.0).sqrt(), (late[j] / 5000.0).sqrt());
        let rel = (late[j] / norm[j]).sqrt();
        eprintln!(
            "joint {j}: f approximation rms [0,1) {e:.3e}, [25,30) {l:.3e} (relative {rel:.3e})"
        );
        assert!(l < 0.5 * e && rel < 0.35, "joint {j}");
    }
}

#[test]
fn computed_torque_with_a_perfect_model_tracks_exactly() {
    let model = two_link();
    let cfg = ComputedTorqueConfig {
        kp: 100.0.into(),
        kd: 20.0.into(),
        safe_hold: SafeHoldConfig::default(),
    };
    let mut c = ComputedTorqueController::new(model.clone(), &cfg).unwrap();
    let log = simulate(&mut c, &model, &sine, &SimOptions::new(2, 10.0), |_, _| {});
    let worst = log.max_abs(0, 0.0, 10.0).max(log.max_abs(1, 0.0, 10.0));
    // Only the zero-order hold and the plant's integration separate it from exact
    // tracking: ten times finer control and plant steps shrink the error accordingly.
    let fine = SimOptions {
        control_dt: 1e-4,
        substeps: 2,
        ..SimOptions::new(2, 10.0)
    };
    let mut c_fine = ComputedTorqueController::new(model.clone(), &cfg).unwrap();
    let log_fine = simulate(&mut c_fine, &model, &sine, &fine, |_, _| {});
    let worst_fine = log_fine
        .max_abs(0, 0.0, 10.0)
        .max(log_fine.max_abs(1, 0.0, 10.0));
    eprintln!("computed torque, perfect model: max |e| = {worst:.2e} at 1 kHz, {worst_fine:.2e} at 10 kHz");
    assert!(worst < 5e-4, "max |e| = {worst:.2e}");
    assert!(
        worst_fine < 0.2 * worst,
        "error vanishes with the step: {worst_fine:.2e}"
    );
    assert_torques_valid(&log, c.safe_hold().effort_limits());
    // A 30 % heavier plant: no longer exact (the test can tell the difference).
    let heavy = model.with_scaled_inertias(1.3).unwrap();
    let mut c = ComputedTorqueController::new(model.clone(), &cfg).unwrap();
    let log_heavy = simulate(&mut c, &heavy, &sine, &SimOptions::new(2, 10.0), |_, _| {});
    let worst_heavy = log_heavy.max_abs(0, 0.0, 10.0);
    eprintln!("computed torque, 30 % heavier plant: max |e| = {worst_heavy:.2e}");
    assert!(worst_heavy > 10.0 * worst && worst_heavy < 0.5);
}

#[test]
fn pd_baselines_track_and_gravity_compensation_helps() {
    let model = two_link();
    let mk = |g| {
        PdController::new(
            model.clone(),
            &PdConfig {
                kp: 100.0.into(),
                kd: 10.0.into(),
                gravity_compensation: g,
                safe_hold: SafeHoldConfig::default(),
            },
        )
        .unwrap()
    };
    let (mut pd, mut pdg) = (mk(false), mk(true));
    assert_eq!((pd.name(), pdg.name()), ("pd", "pd_gravity"));
    let opts = SimOptions::new(2, 10.0);
    let l = simulate(&mut pd, &model, &sine, &opts, |_, _| {});
    let lg = simulate(&mut pdg, &model, &sine, &opts, |_, _| {});
    let (r, rg) = (l.rms(0, 2.0, 10.0), lg.rms(0, 2.0, 10.0));
    eprintln!("pd rms j0 {r:.3e}, pd_gravity {rg:.3e}");
    assert!(r < 0.1, "PD tracks roughly");
    assert!(rg < 0.7 * r, "gravity compensation lowers the error");
    assert_torques_valid(&l, pd.safe_hold().effort_limits());
    assert_torques_valid(&lg, pdg.safe_hold().effort_limits());
}

#[test]
fn torques_are_clamped_to_effort_limits() {
    // Huge PD gains and a far reference: the law asks for more than the limits.
    let model = two_link();
    let mut pd = PdController::new(
        model.clone(),
        &PdConfig {
            kp: 1e6.into(),
            kd: 0.0.into(),
            gravity_compensation: false,
            safe_hold: SafeHoldConfig::default(),
        },
    )
    .unwrap();
    let mut tau = [0.0; 2];
    let input = ControlInput {
        time: 0.0,
        q: &[0.0, 0.0],
        qdot: &[0.0, 0.0],
        q_ref: &[2.0, -2.0],
        qdot_ref: &[0.0; 2],
        qddot_ref: &[0.0; 2],
        external_torque_estimate: &[0.0; 2],
    };
    assert!(pd.step(&input, 1e-3, &mut tau).is_ok());
    assert_eq!(tau, [30.0, -20.0]);
}
