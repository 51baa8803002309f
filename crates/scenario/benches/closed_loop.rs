//! Closed-loop speed of experiment A (issue 3 bar: at least 100x real time on one core).
//!
//! * `closed_loop/nn_compensated`: `scenarios/deadzone.toml`'s `nn_compensated` variant
//!   through [`run_variant`], the code path of `admittance run` (setup, trajectory,
//!   sensors, the adaptive neural controller with deadzone compensation, the plant at the
//!   scenario's rate, metrics and the recorded series), for `SIM_SECONDS` simulated
//!   seconds with the metrics window starting half-way.
//! * `closed_loop/nn_compensated_2khz`: the same at a 2 kHz plant rate.
//! * `closed_loop/nn_compensated_fast_plant`: the same at 5 kHz with the plant's two
//!   approximations for speed on ([`FAST_PLANT`]; their accuracy: docs/benchmarks.md).
//! * `closed_loop_parts/*`: a bare loop of sensors, `ClosedLoop` (its controller) and plant
//!   built from the same resolved scenario, timing each part (printed as shares of the loop).
//!
//! After each group the real-time factor (simulated seconds per wall second) is printed
//! from the median of the per-iteration times criterion measured.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use admittance_dynamics::Model;
use admittance_loop::{ClosedLoop, LoopInput, ObserverConfig};
use admittance_scenario::{run_variant, RunOptions, Scenario, ScenarioSource, Trajectory};
use admittance_sim::{Plant, Sensors};
use criterion::{criterion_group, criterion_main, Criterion};

/// Simulated seconds per iteration.
const SIM_SECONDS: f64 = 2.0;
const VARIANT: &str = "nn_compensated";
/// The plant settings of `closed_loop/nn_compensated_fast_plant`: the friction linearised at
/// each plant step's start, the mass matrix held over the control period.
const FAST_PLANT: [&str; 2] = [
    "plant.friction_solve=linearized",
    "plant.hold_mass_matrix=true",
];

/// `scenarios/deadzone.toml`, or the file named by `ADMITTANCE_BENCH_SCENARIO` (to time two
/// builds on the same scenario text while the file changes).
fn scenario_path() -> PathBuf {
    match std::env::var_os("ADMITTANCE_BENCH_SCENARIO") {
        Some(p) => PathBuf::from(p),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/deadzone.toml"),
    }
}

fn source(extra: &[&str]) -> ScenarioSource {
    let mut s = ScenarioSource::load(&scenario_path()).expect("deadzone.toml");
    s.set(&format!("duration={SIM_SECONDS}")).expect("--set");
    s.set(&format!("evaluation_start={}", 0.5 * SIM_SECONDS))
        .expect("--set");
    for a in extra {
        s.set(a).expect("--set");
    }
    s
}

fn median(xs: &mut [f64]) -> f64 {
    xs.sort_by(|a, b| a.total_cmp(b));
    let n = xs.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

fn report(name: &str, per_iter: &mut [f64]) {
    if per_iter.is_empty() {
        return; // filtered out
    }
    let m = median(per_iter);
    println!(
        "{name}: median {:.1} ms per {SIM_SECONDS} s simulated -> real-time factor {:.1}x",
        m * 1e3,
        SIM_SECONDS / m
    );
}

fn closed_loop(c: &mut Criterion) {
    let path = scenario_path();
    let mut group = c.benchmark_group("closed_loop");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(8));
    for (name, extra) in [
        (VARIANT.to_string(), vec![]),
        (
            format!("{VARIANT}_2khz"),
            vec!["plant.rate_hz=2000.0".to_string()],
        ),
        (
            format!("{VARIANT}_fast_plant"),
            FAST_PLANT.iter().map(|s| s.to_string()).collect(),
        ),
    ] {
        let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
        let src = source(&extra);
        let options = RunOptions::default();
        let mut samples = Vec::new();
        group.bench_function(&name, |b| {
            b.iter_custom(|iters| {
                let start = Instant::now();
                for _ in 0..iters {
                    let run = run_variant(&src, &path, Some(VARIANT), &options).expect("run");
                    std::hint::black_box(&run.metrics);
                }
                let elapsed = start.elapsed();
                samples.push(elapsed.as_secs_f64() / iters as f64);
                elapsed
            })
        });
        report(&format!("closed_loop/{name}"), &mut samples);
    }
    group.finish();
}

/// The bare loop: trajectory, sensors, the closed loop (the controller here: no admittance
/// model, no observer), plant; returns the time spent in (sensors, closed loop, plant).
struct Loop {
    scenario: Scenario,
    model: Arc<Model>,
    trajectory: Trajectory,
}

impl Loop {
    fn new() -> Self {
        let src = source(&[]);
        let scenario: Scenario = src.resolve(Some(VARIANT)).expect("scenario");
        let urdf = scenario.urdf_path(&scenario_path());
        let model = Model::from_urdf_file(
            &urdf,
            scenario.arm.base.as_deref(),
            scenario.arm.tip.as_deref(),
        )
        .expect("model");
        let joints: Vec<String> = model.joint_names().map(String::from).collect();
        let trajectory = Trajectory::new(
            &scenario.trajectory,
            &joints,
            &admittance_scenario::mid_range(&model),
        );
        Self {
            scenario,
            model: Arc::new(model),
            trajectory,
        }
    }

    /// Returns the time in (sensors, closed loop, plant) and the Newton iterations per
    /// plant step.
    fn run(&self) -> ([Duration; 3], f64) {
        let n = self.model.nq();
        let (mut q_d, mut qd_d, mut qdd_d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        self.trajectory.eval(0.0, &mut q_d, &mut qd_d, &mut qdd_d);
        let mut pc = self.scenario.plant.clone();
        pc.initial_q = q_d.clone();
        if let Some(seed) = self.scenario.seed {
            pc.sensors.seed = seed;
        }
        let mut plant = Plant::new(&self.model, &pc).expect("plant");
        let mut sensors = Sensors::new(&self.model, &pc.sensors, pc.control_rate_hz).expect("s");
        // The scenario's controller alone: no admittance model, no estimate.
        let mut config = self.scenario.loop_config();
        config.admittance = None;
        config.task_admittance = None;
        config.observer = ObserverConfig::default();
        let mut closed_loop = ClosedLoop::from_config(&self.model, &config, None).expect("loop");
        let dt = closed_loop.dt();
        let steps = (SIM_SECONDS / dt).round() as usize;
        let zeros = vec![0.0; n];
        let mut parts = [Duration::ZERO; 3];
        for k in 0..steps {
            let t = k as f64 * dt;
            self.trajectory.eval(t, &mut q_d, &mut qd_d, &mut qdd_d);
            let t0 = Instant::now();
            let m = sensors
                .sample(t, plant.q(), closed_loop.torque())
                .expect("sample");
            let t1 = Instant::now();
            let _ = closed_loop.step(&LoopInput {
                time: t,
                q_d: &q_d,
                qdot_d: &qd_d,
                qddot_d: &qdd_d,
                measurement: m,
                true_external_torque: &zeros,
            });
            let t2 = Instant::now();
            plant.step_control(closed_loop.torque()).expect("plant");
            let t3 = Instant::now();
            parts[0] += t1 - t0;
            parts[1] += t2 - t1;
            parts[2] += t3 - t2;
        }
        std::hint::black_box(plant.q());
        let c = plant.counters();
        (parts, c.newton_iterations as f64 / c.steps.max(1) as f64)
    }
}

fn closed_loop_parts(c: &mut Criterion) {
    let lp = Loop::new();
    let mut group = c.benchmark_group("closed_loop_parts");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(8));
    let mut samples = Vec::new();
    let mut totals = [Duration::ZERO; 3];
    let mut runs = 0u64;
    let mut newton = 0.0;
    group.bench_function(VARIANT, |b| {
        b.iter_custom(|iters| {
            let start = Instant::now();
            for _ in 0..iters {
                let (p, it) = lp.run();
                newton = it;
                runs += 1;
                for (t, p) in totals.iter_mut().zip(p) {
                    *t += p;
                }
            }
            let elapsed = start.elapsed();
            samples.push(elapsed.as_secs_f64() / iters as f64);
            elapsed
        })
    });
    group.finish();
    if samples.is_empty() {
        return; // filtered out
    }
    report(&format!("closed_loop_parts/{VARIANT}"), &mut samples);
    let all: f64 = totals.iter().map(Duration::as_secs_f64).sum();
    let steps = (SIM_SECONDS * lp.scenario.plant.control_rate_hz).round();
    for (name, t) in ["sensors", "closed loop", "plant"].iter().zip(totals) {
        let t = t.as_secs_f64();
        println!(
            "  {name}: {:.1}% of the loop, {:.2} us per control step",
            100.0 * t / all,
            t / (runs.max(1) as f64 * steps) * 1e6
        );
    }
    println!("  Newton iterations per plant step: {newton:.2}");
    let m = median(&mut samples);
    println!(
        "  per control step: {:.2} us total ({} plant substeps of {:.0} Hz)",
        m / steps * 1e6,
        (lp.scenario.plant.rate_hz / lp.scenario.plant.control_rate_hz).round(),
        lp.scenario.plant.rate_hz
    );
}

criterion_group!(benches, closed_loop, closed_loop_parts);
criterion_main!(benches);
