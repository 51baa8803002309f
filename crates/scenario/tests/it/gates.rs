//! Issue 34 in the scenario runner: one absurd but finite sample (a torque reading of
//! 1e300 N m, an angle of 1e20 rad; `[[plant.sensors.faults]]` of kind `torque_spike`,
//! `angle_spike`) is refused by the plausibility gates before the signal chain sees it,
//! counted in `gated_samples`, and the estimate is back on that of the run without the
//! spike within a second, for the momentum observer and the hybrid (momentum plus a
//! learned residual). Without spikes the gates do not fire on these runs.

use crate::common;
use common::{metric, number, record, scenario_path};

use admittance_scenario::{run_variant, RunOptions, ScenarioSource, VariantRun};
use serde_json::json;

/// The spike's sample (s); the contact on s0 lasts from 1 s to the end (3.5 s).
const SPIKE_AT: f64 = 2.0;

fn run(variant: &str, extra: &[String]) -> VariantRun {
    let path = scenario_path("admittance.toml");
    let mut source = ScenarioSource::load(&path).unwrap();
    let base = [
        "duration=3.5".to_string(),
        "evaluation_start=0.5".to_string(),
        "output.decimation=1".to_string(),
        "plant.environment.joint_springs=[{ joints = [\"left_s0\"], mass = [0.01], damping = [0.15], stiffness = [1.1], t_start = 1.0 }]".to_string(),
    ];
    for o in base.iter().chain(extra) {
        source.set(o).unwrap_or_else(|e| panic!("{o}: {e}"));
    }
    run_variant(&source, &path, Some(variant), &RunOptions::default())
        .unwrap_or_else(|e| panic!("{variant}: {e}"))
}

/// One sample's spike on `joint` (a window shorter than the 1 ms period around it).
fn spike(kind: &str, joint: &str, value: f64) -> String {
    format!(
        "plant.sensors.faults=[{{ kind = \"{kind}\", joints = [\"{joint}\"], t_start = {}, t_end = {}, value = {value:e} }}]",
        SPIKE_AT - 5e-4,
        SPIKE_AT + 5e-4
    )
}

/// Largest `|tau_ext_hat - tau_ext_hat(clean)|` over the joints and the samples at `t` in
/// `[from, to)`.
fn estimate_gap(run: &VariantRun, clean: &VariantRun, from: f64, to: f64) -> f64 {
    let s = &run.series;
    let t = s.column("t").unwrap();
    let cols: Vec<usize> = run
        .joints
        .iter()
        .map(|j| s.column(&format!("tau_ext_hat.{j}")).unwrap())
        .collect();
    assert_eq!(s.rows.len(), clean.series.rows.len());
    let mut gap: f64 = 0.0;
    for (a, b) in s.rows.iter().zip(&clean.series.rows) {
        if a[t] >= from && a[t] < to {
            for &c in &cols {
                assert!(a[c].is_finite(), "t = {}: estimate {}", a[t], a[c]);
                gap = gap.max((a[c] - b[c]).abs());
            }
        }
    }
    gap
}

/// The run completed with status OK metrics and the spike refused once by `gate`.
fn check_refused_once(run: &VariantRun, gate: &str, faults: f64) {
    let mut want = json!({"angle": 0, "jump": 0, "torque": 0, "velocity": 0});
    want[gate] = json!(1);
    assert_eq!(metric(run, "gated_samples"), want, "{}", run.name);
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    assert_eq!(number(run, "nonfinite_torques"), 0.0);
    assert_eq!(number(run, "torque_limit_violations"), 0.0);
    assert_eq!(number(run, "reference_bound_violations"), 0.0);
    // A refused angle takes the NaN path: the controller's safe hold for that one period.
    assert_eq!(number(run, "faults"), faults, "{}", run.name);
}

/// Both spikes against the clean run of `variant`; `tolerance` (N m) on the estimate from
/// a second after the spike on.
fn spikes_are_refused_and_forgotten(variant: &str, extra: &[String], tolerance: f64) {
    let clean = run(variant, extra);
    assert_eq!(
        metric(&clean, "gated_samples"),
        json!({"angle": 0, "jump": 0, "torque": 0, "velocity": 0})
    );
    // The contact is seen: the tolerance is small against the estimate itself.
    let s0 = clean.series.column("tau_ext_hat.left_s0").unwrap();
    let seen = clean.series.rows.last().unwrap()[s0].abs();
    assert!(seen > 5.0 * tolerance, "{variant}: estimate {seen}");
    for (kind, gate, joint, value, faults) in [
        ("torque_spike", "torque", "left_s1", 1e300, 0.0),
        ("angle_spike", "angle", "left_e1", 1e20, 1.0),
    ] {
        let mut with = extra.to_vec();
        with.push(spike(kind, joint, value));
        let spiked = run(variant, &with);
        check_refused_once(&spiked, gate, faults);
        // Bit for bit the clean run until the spike.
        assert_eq!(estimate_gap(&spiked, &clean, 0.0, SPIKE_AT - 1e-6), 0.0);
        let peak = estimate_gap(&spiked, &clean, SPIKE_AT, f64::INFINITY);
        let gap = estimate_gap(&spiked, &clean, SPIKE_AT + 1.0, f64::INFINITY);
        eprintln!(
            "{variant} {kind} {value:e}: estimate off the clean run's by at most {peak:.2e} N m after the spike, {gap:.2e} N m from 1 s after it (clean s0 estimate {seen:.2} N m)"
        );
        assert!(gap < tolerance, "{variant} {kind}: {gap} N m");
        if kind == "angle_spike" {
            // Refused, the spike is a dropped reading: bit for bit a NaN in its place.
            let mut nan = extra.to_vec();
            nan.push(spike("nan", joint, 0.0).replace(", value = 0e0", ""));
            let dropped = run(variant, &nan);
            let bits = |r: &VariantRun| -> Vec<Vec<u64>> {
                let rows = r.series.rows.iter();
                rows.map(|row| row.iter().map(|x| x.to_bits()).collect())
                    .collect()
            };
            assert!(bits(&dropped) == bits(&spiked), "{variant}");
        }
    }
}

#[test]
fn a_spike_is_gated_and_the_momentum_estimate_recovers_within_a_second() {
    spikes_are_refused_and_forgotten("momentum", &[], 0.02);
}

/// The hybrid observer (momentum on the 20%-wrong URDF plus a residual network trained on
/// 40 s of free motion, as `learned_observers.rs` trains it). The pure learned observer of
/// that test is left out: on this short contact its estimate is poor (NRMSE 75) and the
/// arm it drives moves faster than three times its velocity limits, so that the jump gate
/// fires on genuine samples in the clean run too (334 times).
#[test]
fn a_spike_is_gated_and_the_hybrid_estimate_recovers_within_a_second() {
    let root = tempfile::tempdir().unwrap();
    let train = record("free_motion.toml", 40.0, &root.path().join("train"));
    let validation = record(
        "free_motion_validation.toml",
        12.0,
        &root.path().join("val"),
    );
    let cache = root.path().join("cache").display().to_string();
    let training = format!(
        "observer.training={{ data = {train:?}, validation = {validation:?}, nodes = 150, cache_dir = {cache:?} }}"
    );
    spikes_are_refused_and_forgotten("hybrid_urdf", &[training], 0.02);
}
