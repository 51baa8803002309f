//! Accuracy of the plant's speed approximations (`friction_solve`, `hold_mass_matrix`,
//! `newton_tolerance`, or a coarser `rate_hz`) against the exact plant, on experiment A's plant
//! (scenarios/deadzone.toml: friction, the s0 deadzone, the s1 spring) and desired motion,
//! with no sensor noise or quantisation in the way (those make the full closed loop's
//! rounding differences grow, docs/benchmarks.md "Closed loop"):
//!
//! * `local`: at every control period the approximate plant is set to the exact plant's
//!   state and both take the period with the same command; the RMS and largest difference
//!   of the joint angles (rad) and velocities (rad/s) after the period;
//! * `loop`: each plant in its own closed loop with the `pd` variant's gains on its true
//!   state, for `--seconds` (40); the RMS and largest joint-angle difference (rad).
//!
//! Usage: cargo run --release -p admittance-sim --example plant_approximation --
//!        [--set KEY=VALUE]... [--seconds S]
//! where KEY is `friction_solve`, `hold_mass_matrix`, `newton_tolerance` or `rate_hz`,
//! e.g. `--set friction_solve=linearized --set hold_mass_matrix=true`.

use std::path::Path;

use admittance_dynamics::Model;
use admittance_sim::{FrictionSolve, Plant, PlantConfig};

const KP: [f64; 7] = [240.0, 360.0, 180.0, 120.0, 24.0, 24.0, 2.4];
const KD: [f64; 7] = [20.0, 30.0, 15.0, 10.0, 2.0, 2.0, 0.2];
const OFFSET: [f64; 7] = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
/// s0's desired motion: `sin(2 pi t / PERIOD)` (scenarios/deadzone.toml).
const PERIOD: f64 = 4.488;

/// Running RMS and maximum of absolute differences.
#[derive(Default)]
struct Stat {
    sum2: f64,
    count: usize,
    max: f64,
}

impl Stat {
    fn add(&mut self, a: &[f64], b: &[f64]) {
        for (x, y) in a.iter().zip(b) {
            let d = x - y;
            self.sum2 += d * d;
            self.count += 1;
            self.max = self.max.max(d.abs());
        }
    }
    fn show(&self) -> String {
        format!(
            "RMS {:.2e}, max {:.2e}",
            (self.sum2 / self.count.max(1) as f64).sqrt(),
            self.max
        )
    }
}

fn pd(t: f64, q: &[f64], v: &[f64], tau: &mut [f64]) {
    let w = 2.0 * std::f64::consts::PI / PERIOD;
    for i in 0..7 {
        let (qd, vd) = if i == 0 {
            ((w * t).sin(), w * (w * t).cos())
        } else {
            (OFFSET[i], 0.0)
        };
        tau[i] = KP[i] * (qd - q[i]) + KD[i] * (vd - v[i]);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(root.join("scenarios/deadzone.toml")).expect("scenario");
    let table: toml::Table = toml::from_str(&text).expect("toml");
    let mut exact: PlantConfig = table["plant"].clone().try_into().expect("[plant]");
    exact.initial_q = OFFSET.to_vec();
    let mut seconds = 40.0;
    let mut approx = exact.clone();
    let mut k = 0;
    while k < args.len() {
        match (args[k].as_str(), args.get(k + 1)) {
            ("--seconds", Some(v)) => seconds = v.parse().expect("--seconds S"),
            ("--set", Some(kv)) => {
                let (key, value) = kv.split_once('=').expect("--set KEY=VALUE");
                match key {
                    "hold_mass_matrix" => approx.hold_mass_matrix = value.parse().expect("bool"),
                    "newton_tolerance" => approx.newton_tolerance = value.parse().expect("f64"),
                    "friction_solve" => {
                        approx.friction_solve = match value {
                            "newton" => FrictionSolve::Newton,
                            "linearized" => FrictionSolve::Linearized,
                            other => panic!("friction_solve: newton or linearized, not {other}"),
                        }
                    }
                    "rate_hz" => approx.rate_hz = value.parse().expect("f64"),
                    _ => panic!("unknown key {key}"),
                }
            }
            (a, _) => panic!("unknown argument {a}"),
        }
        k += 2;
    }
    let model = Model::from_urdf_file(
        &root.join("models/baxter_left_arm.urdf"),
        Some("base"),
        Some("left_hand"),
    )
    .expect("model");
    let steps = (seconds * exact.control_rate_hz).round() as usize;
    let dt = 1.0 / exact.control_rate_hz;
    let mut tau = [0.0; 7];

    // One period from the exact plant's state.
    let mut e = Plant::new(&model, &exact).expect("exact plant");
    let mut a = Plant::new(&model, &approx).expect("approximate plant");
    let (mut local_q, mut local_v) = (Stat::default(), Stat::default());
    for k in 0..steps {
        pd(k as f64 * dt, e.q(), e.qdot(), &mut tau);
        a.set_state(e.q(), e.qdot()).expect("state");
        e.step_control(&tau).expect("step");
        a.step_control(&tau).expect("step");
        local_q.add(e.q(), a.q());
        local_v.add(e.qdot(), a.qdot());
    }
    println!(
        "local (one control period from the same state): q {} rad, qdot {} rad/s",
        local_q.show(),
        local_v.show()
    );

    // Two closed loops.
    let mut e = Plant::new(&model, &exact).expect("exact plant");
    let mut a = Plant::new(&model, &approx).expect("approximate plant");
    let mut tau_a = [0.0; 7];
    let mut q = Stat::default();
    for k in 0..steps {
        let t = k as f64 * dt;
        pd(t, e.q(), e.qdot(), &mut tau);
        pd(t, a.q(), a.qdot(), &mut tau_a);
        e.step_control(&tau).expect("step");
        a.step_control(&tau_a).expect("step");
        if (k + 1) % 10 == 0 {
            q.add(e.q(), a.q());
        }
    }
    println!(
        "loop ({seconds} s, PD on the true state, every 10 ms): q {} rad; Newton iterations per plant step {:.2} (exact {:.2})",
        q.show(),
        a.counters().newton_iterations as f64 / a.counters().steps.max(1) as f64,
        e.counters().newton_iterations as f64 / e.counters().steps.max(1) as f64,
    );
}
