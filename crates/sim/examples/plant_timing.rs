//! Per-step timing of the plant on an arm, printed as `<name> <median ns>` lines, for the
//! side-by-side comparison with MuJoCo's `mj_step` (scripts/bench/compare_mujoco.sh),
//! which times MuJoCo the same way: from a mid-range pose (the middle of every joint's
//! position limits) at rest, a constant joint torque, timed batches of `--steps` (100)
//! steps, the state reset to the pose every 10 batches (outside the timed region), median
//! over `--batches` (1001) batches of (batch time / steps). Short batches keep the median
//! clear of preemption on a loaded machine.
//!
//! Lines: `semi_implicit_euler` (MuJoCo's scheme, frictionless, no environment: what
//! `mj_step` computes), `rk4_split` (the default integrator, same arm), then
//! `semi_implicit_euler_cholesky` and `rk4_split_cholesky` (CRBA + Cholesky forced instead
//! of ABA), `semi_implicit_euler_friction` and `rk4_split_friction` (Coulomb + viscous
//! friction on every joint, implicit: CRBA + Newton), `semi_implicit_euler_scenario` and
//! `rk4_split_scenario` (experiment A's plant: that friction, a deadzone on the first
//! joint and the s1 counterbalance spring, whose gravity-fraction law costs one gravity
//! pass of the nominal model per force evaluation).
//!
//! With `--check FILE` it instead writes a JSON file for the agreement check: per-joint
//! body masses, M and G at the pose, and the joint angles every `--check-every` (100)
//! steps along `--check-steps` (1000) steps of free fall (zero torque, frictionless) from
//! the pose under both integrators.
//!
//! Usage: cargo run --release -p admittance-sim --example plant_timing -- [URDF [TIP]]
//!        [--dt SECONDS] [--steps N] [--batches N] [--only NAME]
//!        [--check FILE [--check-steps N] [--check-every K]]

use std::hint::black_box;
use std::time::Instant;

use admittance_dynamics::{crba, gravity_torque, Data, Model};
use admittance_sim::{DeadzoneConfig, FrictionConfig, Integrator, Plant, PlantConfig, Solver};

/// Batches between resets of the state to the pose (`RESET_EVERY * steps` steps, 0.2 s
/// at the defaults).
const RESET_EVERY: usize = 10;

fn arg_value(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let positional: Vec<&String> = {
        let mut out = Vec::new();
        let mut skip = false;
        for a in args.iter().skip(1) {
            if skip {
                skip = false;
                continue;
            }
            if a.starts_with("--") {
                skip = true;
                continue;
            }
            out.push(a);
        }
        out
    };
    let urdf = positional
        .first()
        .map(|s| s.as_str())
        .unwrap_or("models/baxter_left_arm.urdf");
    let tip = positional.get(1).map(|s| s.as_str()).unwrap_or("left_hand");
    let dt: f64 = arg_value(&args, "--dt")
        .and_then(|s| s.parse().ok())
        .unwrap_or(2e-4);
    let steps: usize = arg_value(&args, "--steps")
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    let batches: usize = arg_value(&args, "--batches")
        .and_then(|s| s.parse().ok())
        .unwrap_or(1001);
    let model = match Model::from_urdf_file(urdf.as_ref(), None, Some(tip)) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let n = model.nq();
    let q0: Vec<f64> = model
        .position_limits()
        .map(|(lo, hi)| {
            if lo.is_finite() && hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                0.0
            }
        })
        .collect();
    let tau: Vec<f64> = (0..n)
        .map(|i| 0.5 * (-1.0f64).powi(i as i32) / (1.0 + i as f64))
        .collect();

    let config = |integrator: Integrator, solver: Solver, friction: bool| -> PlantConfig {
        PlantConfig {
            rate_hz: 1.0 / dt,
            control_rate_hz: 1.0 / dt,
            integrator,
            solver,
            initial_q: q0.clone(),
            friction: if friction {
                vec![FrictionConfig {
                    joint: "*".into(),
                    viscous: 0.5,
                    coulomb: 0.3,
                    v_s: 0.01,
                }]
            } else {
                Vec::new()
            },
            ..PlantConfig::default()
        }
    };
    // Experiment A's plant: friction on every joint, the s0 deadzone, the s1 spring.
    let scenario = |integrator: Integrator| -> PlantConfig {
        let mut c = config(integrator, Solver::Auto, true);
        c.deadzones = vec![DeadzoneConfig {
            joint: model.joints[0].name.clone(),
            d_left: -0.49,
            d_right: 0.49,
            ..Default::default()
        }];
        c.spring.enabled = model.joint_index(&c.spring.joint).is_some();
        c
    };

    if let Some(path) = arg_value(&args, "--check") {
        let check_steps: usize = arg_value(&args, "--check-steps")
            .and_then(|s| s.parse().ok())
            .unwrap_or(1000);
        let mut data = Data::new(&model);
        let m = crba(&model, &mut data, &q0).expect("crba").clone();
        let g = gravity_torque(&model, &mut data, &q0)
            .expect("gravity")
            .clone();
        let mut out = String::from("{\n");
        out += &format!(
            "  \"joint_names\": {:?},\n",
            model.joint_names().collect::<Vec<_>>()
        );
        out += &format!(
            "  \"body_mass\": {:?},\n",
            model.bodies.iter().map(|b| b.mass).collect::<Vec<_>>()
        );
        out += &format!("  \"q0\": {q0:?},\n  \"dt\": {dt:e},\n  \"steps\": {check_steps},\n");
        let rows: Vec<String> = (0..n)
            .map(|i| format!("{:?}", (0..n).map(|j| m[(i, j)]).collect::<Vec<_>>()))
            .collect();
        out += &format!("  \"mass_matrix\": [{}],\n", rows.join(", "));
        out += &format!("  \"gravity\": {:?},\n", g.as_slice());
        let every: usize = arg_value(&args, "--check-every")
            .and_then(|s| s.parse().ok())
            .unwrap_or(100)
            .max(1);
        out += &format!("  \"every\": {every},\n");
        for (k, integrator) in [Integrator::SemiImplicitEuler, Integrator::Rk4Split]
            .into_iter()
            .enumerate()
        {
            let mut plant =
                Plant::new(&model, &config(integrator, Solver::Auto, false)).expect("plant");
            let zero = vec![0.0; n];
            let mut rows = Vec::new();
            for s in 1..=check_steps {
                plant.step(&zero).expect("step");
                if s % every == 0 {
                    rows.push(format!("{:?}", plant.q()));
                }
            }
            let sep = if k == 0 { "," } else { "" };
            out += &format!(
                "  \"trajectory_{}\": [{}]{sep}\n",
                integrator.name(),
                rows.join(", ")
            );
        }
        out += "}\n";
        if let Err(e) = std::fs::write(&path, out) {
            eprintln!("{path}: {e}");
            std::process::exit(2);
        }
        return;
    }

    let only = arg_value(&args, "--only");
    let time = |name: &str, cfg: PlantConfig| {
        if only.as_deref().is_some_and(|o| o != name) {
            return;
        }
        let mut plant = Plant::new(&model, &cfg).expect("plant");
        let zero_v = vec![0.0; n];
        let mut per_step = Vec::with_capacity(batches);
        for b in 0..batches + 3 {
            if b % RESET_EVERY == 0 {
                plant.set_state(&q0, &zero_v).expect("state");
            }
            let start = Instant::now();
            for _ in 0..steps {
                black_box(plant.step(black_box(&tau)).ok());
            }
            let ns = start.elapsed().as_nanos() as f64 / steps as f64;
            if b >= 3 {
                per_step.push(ns);
            }
        }
        per_step.sort_by(|a, b| a.total_cmp(b));
        if std::env::var_os("PLANT_TIMING_VERBOSE").is_some() {
            let c = plant.counters();
            eprintln!(
                "# {name}: {:.2} Newton iterations per step",
                c.newton_iterations as f64 / c.steps as f64
            );
        }
        println!("{name} {:.1}", per_step[per_step.len() / 2]);
    };
    use Integrator::{Rk4Split, SemiImplicitEuler};
    time(
        "semi_implicit_euler",
        config(SemiImplicitEuler, Solver::Auto, false),
    );
    time("rk4_split", config(Rk4Split, Solver::Auto, false));
    time(
        "semi_implicit_euler_cholesky",
        config(SemiImplicitEuler, Solver::Cholesky, false),
    );
    time(
        "rk4_split_cholesky",
        config(Rk4Split, Solver::Cholesky, false),
    );
    time(
        "semi_implicit_euler_friction",
        config(SemiImplicitEuler, Solver::Auto, true),
    );
    time("rk4_split_friction", config(Rk4Split, Solver::Auto, true));
    time("semi_implicit_euler_scenario", scenario(SemiImplicitEuler));
    time("rk4_split_scenario", scenario(Rk4Split));
}
