//! `ClosedLoop::from_config`: the same loop as one wired by hand from its parts, and its
//! errors at their keys.

use std::sync::Arc;

use admittance_control::{
    Admittance, AdmittanceConfig, MomentumObserver, MomentumObserverConfig, NeuralController,
    NeuralControllerConfig,
};
use admittance_dynamics::Model;
use admittance_loop::{
    ClosedLoop, Compliance, EstimateSource, EstimateToController, LoopConfig, LoopController,
    LoopInput, LoopParts, ObserverStage, ObserverStageSettings, SignalChain,
};

const POSE: [f64; 7] = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];

fn baxter() -> Model {
    let urdf = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/baxter_left_arm.urdf"
    );
    Model::from_urdf_file(urdf.as_ref(), Some("base"), Some("left_hand")).unwrap()
}

const CONFIG: &str = r#"
control_rate_hz = 1000.0
[controller]
kind = "neural"
subtract_estimate = false
[admittance]
damping = 3.0
stiffness = 5.0
[observer]
kind = "momentum"
cutoff_hz = 5.0
input_filter_hz = 10.0
warmup = 0.1
"#;

fn by_hand(model: &Model) -> ClosedLoop {
    let nominal = Arc::new(model.clone());
    let observer = MomentumObserver::new(nominal.clone(), &MomentumObserverConfig::default());
    let settings = ObserverStageSettings {
        input_filter_hz: 10.0,
        cutoff_hz: 5.0,
        warmup: 0.1,
        delayed_torque: false,
        rate_hz: 1000.0,
    };
    let admittance = AdmittanceConfig {
        saturation: None,
        ..AdmittanceConfig::paper()
    };
    ClosedLoop::new(LoopParts {
        controller: LoopController::Neural(Box::new(
            NeuralController::new(nominal, &NeuralControllerConfig::default()).unwrap(),
        )),
        admittance: Some(Compliance::Joint(Admittance::new(7, &admittance).unwrap())),
        estimate: EstimateSource::Observer(Box::new(
            ObserverStage::new(Box::new(observer.unwrap()), &settings).unwrap(),
        )),
        estimate_to_controller: EstimateToController::OnlyWithoutAdmittance,
        dt: 1e-3,
    })
}

/// Steps `lp` against a pose that moves a little and a command fed back as the reading's
/// torque; returns every torque.
fn run(lp: &mut ClosedLoop) -> Vec<f64> {
    let mut chain = SignalChain::new(7, 40.0, 1000.0).unwrap();
    let zeros = [0.0; 7];
    let mut out = Vec::new();
    for k in 0..400 {
        let t = k as f64 * 1e-3;
        let mut q = POSE;
        q[0] += 0.05 * (3.0 * t).sin();
        let m = chain.sample(t, &q, lp.torque()).unwrap();
        let status = lp.step(&LoopInput {
            time: t,
            q_d: &POSE,
            qdot_d: &zeros,
            qddot_d: &zeros,
            measurement: m,
            true_external_torque: &zeros,
        });
        assert!(status.observer_ok);
        out.extend_from_slice(lp.torque());
        out.extend_from_slice(lp.external_torque_estimate());
    }
    out
}

#[test]
fn the_configured_loop_is_the_hand_wired_one_bit_for_bit() {
    let model = baxter();
    let config: LoopConfig = toml::from_str(CONFIG).unwrap();
    let mut configured = ClosedLoop::from_config(&model, &config, None).unwrap();
    assert!(configured.neural().is_some() && configured.admittance().is_some());
    let a = run(&mut configured);
    let b = run(&mut by_hand(&model));
    assert!(a.iter().any(|x| *x != 0.0));
    let same = a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits());
    assert!(same, "the configured loop differs from the hand-wired one");
}

#[test]
fn errors_name_their_keys() {
    let model = baxter();
    let learned: LoopConfig =
        toml::from_str("[controller]\nkind = \"neural\"\n[observer]\nkind = \"learned\"\n")
            .unwrap();
    let e = ClosedLoop::from_config(&model, &learned, None)
        .err()
        .unwrap();
    assert_eq!(e.key(), "observer.kind", "{e}");
    let bad_gain: LoopConfig =
        toml::from_str("[controller]\nkind = \"neural\"\n[controller.neural]\nk1 = -1.0\n")
            .unwrap();
    let e = ClosedLoop::from_config(&model, &bad_gain, None)
        .err()
        .unwrap();
    assert!(e.key().starts_with("controller.neural.k1"), "{e}");
    let short: LoopConfig =
        toml::from_str("[controller]\nkind = \"pd\"\npd = { kp = [1.0, 2.0], kd = 1.0 }\n")
            .unwrap();
    let e = ClosedLoop::from_config(&model, &short, None).err().unwrap();
    assert!(e.key().starts_with("controller.pd.kp"), "{e}");
}
