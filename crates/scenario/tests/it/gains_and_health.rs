//! The gain rules when a scenario loads (warnings naming the file, line, key, joint and a
//! value to use) and the health rules a finished run is judged by (summary.json's `health`).

use crate::common;
use common::scenario_path;

use admittance_scenario::{gain_warnings, run_scenario, RunOptions, ScenarioSource};

/// Every committed scenario and every variant loads without a gain warning.
#[test]
fn the_committed_scenarios_pass_the_gain_rules() {
    let dir = scenario_path("deadzone.toml")
        .parent()
        .unwrap()
        .to_path_buf();
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let source = ScenarioSource::load(&path).unwrap();
        let mut variants: Vec<Option<String>> =
            source.variant_names().into_iter().map(Some).collect();
        if variants.is_empty() {
            variants.push(None);
        }
        for v in variants {
            let w = gain_warnings(&source, &path, v.as_deref()).unwrap();
            if path.ends_with("dynamic_nodes.toml") {
                // Experiment C swings e1 and s1 under s0: s0's inertia reaches 2.87 kg m^2
                // and K1 I 34 > 30, a warning the file explains (a sufficient condition).
                assert_eq!(w.len(), 1, "{w:#?}");
                assert!(
                    w[0].contains("K2 of left_s0 is 30") && w[0].contains("dynamic_nodes.toml:"),
                    "{}",
                    w[0]
                );
                continue;
            }
            assert!(w.is_empty(), "{} {v:?}: {w:#?}", path.display());
            checked += 1;
        }
    }
    assert!(checked >= 25, "only {checked} variants checked");
}

/// Experiment A with the paper's uniform K2 = 6: s0, s1, e0, e1 are under K1 I (17.5, 12.4,
/// 7.9, 6.6), the wrist's w0, w1, w2 over the velocity filter's bandwidth; each warning
/// names its joint and a value that passes.
#[test]
fn a_bad_gain_names_the_joint_and_a_value_that_passes() {
    let path = scenario_path("deadzone.toml");
    let mut source = ScenarioSource::load(&path).unwrap();
    source.set("controller.neural.k2=6.0").unwrap();
    let w = gain_warnings(&source, &path, Some("nn_compensated")).unwrap();
    assert_eq!(w.len(), 7, "{w:#?}");
    for (j, rule) in [
        ("left_s0", "K1 I"),
        ("left_s1", "K1 I"),
        ("left_e0", "K1 I"),
        ("left_e1", "K1 I"),
        ("left_w0", "crosses over"),
        ("left_w1", "crosses over"),
        ("left_w2", "crosses over"),
    ] {
        assert!(
            w.iter()
                .any(|l| l.contains(&format!("({j})")) && l.contains(rule)),
            "{j} {rule}: {w:#?}"
        );
    }
    let s0 = w.iter().find(|l| l.contains("(left_s0)")).unwrap();
    // Located where the value was written: here the override.
    assert!(
        s0.starts_with("--set controller.neural.k2=6.0: key `controller.neural.k2`"),
        "{s0}"
    );
    assert!(
        s0.contains("K1 I") && s0.contains("set controller.neural.k2[0] (left_s0) to"),
        "{s0}"
    );
    // The suggested values pass.
    let suggested: Vec<f64> = w
        .iter()
        .map(|l| {
            l.rsplit(" to ")
                .next()
                .unwrap()
                .split_whitespace()
                .next()
                .unwrap()
                .parse()
                .unwrap()
        })
        .collect();
    let mut k2 = [6.0; 7];
    for (l, s) in w.iter().zip(&suggested) {
        let j = [
            "left_s0", "left_s1", "left_e0", "left_e1", "left_w0", "left_w1", "left_w2",
        ]
        .iter()
        .position(|j| l.contains(&format!("({j})")))
        .unwrap();
        k2[j] = *s;
    }
    let mut fixed = ScenarioSource::load(&path).unwrap();
    fixed.set(&format!("controller.neural.k2={k2:?}")).unwrap();
    let w = gain_warnings(&fixed, &path, Some("nn_compensated")).unwrap();
    assert!(w.is_empty(), "{k2:?}: {w:#?}");
}

/// A run that breaks a health rule records the verdict in summary.json, with the threshold
/// the variant was judged by.
#[test]
fn a_broken_health_rule_is_recorded_and_kept_apart_from_divergence() {
    let path = scenario_path("deadzone.toml");
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("run");
    let summary = run_scenario(
        &path,
        &dir,
        Some("nn_compensated"),
        &[
            "duration=2".into(),
            "evaluation_start=1".into(),
            "health.max_hand_error=1e-6".into(),
        ],
        &RunOptions::default(),
        false,
        |_, _, _| {},
        |_| Ok(()),
    )
    .unwrap();
    assert!(summary.failures.is_empty(), "{:?}", summary.failures);
    assert_eq!(
        summary.health_failures.len(),
        1,
        "{:?}",
        summary.health_failures
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    let h = &json["health"];
    assert_eq!(h["status"], "failure");
    let v = &h["variants"]["nn_compensated"];
    assert_eq!(v["settings"]["max_hand_error"], 1e-6);
    assert_eq!(v["verdicts"][0]["rule"], "hand_error");
    assert_eq!(v["verdicts"][0]["severity"], "failure");
    assert!(v["verdicts"][0]["value"].as_f64().unwrap() > 1e-6);
}
