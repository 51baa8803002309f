//! The cost of the C ABI on a shared machine: `adm_step` against the Rust loop's step it
//! wraps ([`RobotLoop::step`]), in alternating blocks so that both see the same load.
//! Each round times `BLOCK` steps of one, then `BLOCK` of the other (which goes first
//! alternates); the medians over the rounds of the per-step times, and of the per-round
//! difference, are printed. Blocks are short, so the medians leave out preemption by other
//! processes (a block of milliseconds on a loaded machine times their work too). Same loop and inputs as `benches/step.rs`
//! (the deployment of scenarios/admittance.toml's variant `momentum`, 7 joints, measured torques).
//!
//! Run: `cargo run --release -p admittance-ffi --example step_cost [ROUNDS]`

use std::ffi::CString;
use std::hint::black_box;
use std::time::Instant;

use admittance_ffi::*;

#[path = "../tests/common/mod.rs"]
mod common;

const N: usize = 7;
/// Steps per timed block: short (about 25 us), so that a block is rarely preempted on a
/// loaded machine and the medians leave out the blocks that were.
const BLOCK: usize = 10;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rounds: usize = std::env::args().nth(1).map_or(Ok(30_000), |s| s.parse())?;
    let (_tmp, dir) = common::deploy("momentum");
    let mut rust = RobotLoop::load(&dir, &[]).expect("deployment folder");
    // One trajectory period (12 s): the arm tracking the scenario's desired motion with a
    // small error, with measured torques; index `k` is time `k` ms.
    let (mut q_d, mut qd, mut qdd) = ([0.0; N], [0.0; N], [0.0; N]);
    let mut ring: Vec<AdmInput> = (0..12_000)
        .map(|k| {
            let t = k as f64 * 1e-3;
            desired_at(t, &mut q_d, &mut qd, &mut qdd);
            let mut inp = AdmInput::ZERO;
            inp.n_joints = N as u32;
            inp.flags = ADM_INPUT_TAU | ADM_INPUT_DESIRED;
            for (i, &p) in q_d.iter().enumerate() {
                inp.q[i] = p + 0.01 * (t * (1.0 + i as f64)).sin();
                inp.tau[i] = 0.5 * (3.0 * t).sin();
                inp.q_d[i] = p;
                inp.qdot_d[i] = qd[i];
                inp.qddot_d[i] = qdd[i];
            }
            inp
        })
        .collect();
    let len = ring.len();
    let path = CString::new(dir.to_str().ok_or("path not UTF-8")?)?;
    let config = AdmConfig {
        abi_version: ADM_ABI_VERSION,
        n_joints: N as u32,
        deployment_path: path.as_ptr(),
        overrides: std::ptr::null(),
        flags: 0,
        reserved: 0,
        wrench_damping: 0.0,
    };
    // SAFETY: `config` and its strings outlive the call.
    let h = unsafe { adm_create(&config) };
    if h.is_null() {
        return Err("adm_create failed".into());
    }
    let mut out = AdmOutput::ZERO;
    let (mut k_rust, mut k_c) = (0usize, 0usize);

    let mut rust_block = |ring: &[AdmInput]| {
        let start = Instant::now();
        for _ in 0..BLOCK {
            let inp = &ring[k_rust % len];
            let report = rust.step(&RobotInput {
                time: k_rust as f64 * 1e-3,
                q: black_box(&inp.q[..N]),
                qdot: None,
                tau: Some(black_box(&inp.tau[..N])),
                desired: Some([&inp.q_d[..N], &inp.qdot_d[..N], &inp.qddot_d[..N]]),
            });
            black_box((report, rust.torque()[0]));
            k_rust += 1;
        }
        start.elapsed().as_secs_f64() * 1e9 / BLOCK as f64
    };
    let mut c_block = |ring: &mut [AdmInput]| {
        let start = Instant::now();
        for _ in 0..BLOCK {
            let inp = &mut ring[k_c % len];
            inp.time = k_c as f64 * 1e-3;
            // SAFETY: a live handle, valid input and output.
            let status = unsafe { adm_step(black_box(h), black_box(&*inp), &mut out) };
            black_box((status, out.tau_cmd[0]));
            k_c += 1;
        }
        start.elapsed().as_secs_f64() * 1e9 / BLOCK as f64
    };

    // Warm-up: past the observer's warm-up and the caches.
    rust_block(&ring);
    c_block(&mut ring);
    let (mut rust_ns, mut c_ns, mut diff_ns) = (Vec::new(), Vec::new(), Vec::new());
    for r in 0..rounds {
        let (a, b) = if r % 2 == 0 {
            let a = rust_block(&ring);
            (a, c_block(&mut ring))
        } else {
            let b = c_block(&mut ring);
            (rust_block(&ring), b)
        };
        rust_ns.push(a);
        c_ns.push(b);
        diff_ns.push(b - a);
    }
    // SAFETY: a live handle, no longer used.
    unsafe { adm_destroy(h) };
    println!(
        "step_cost: {rounds} rounds of {BLOCK} steps each: RobotLoop::step median {:.0} ns, \
         adm_step median {:.0} ns, adm_step - RobotLoop::step per round: median {:+.0} ns",
        median(&mut rust_ns),
        median(&mut c_ns),
        median(&mut diff_ns)
    );
    Ok(())
}

/// Experiment B's desired motion: the pose, with s0 at `1.0 sin(2 pi t / 12)`.
fn desired_at(t: f64, q: &mut [f64; N], qd: &mut [f64; N], qdd: &mut [f64; N]) {
    let w = std::f64::consts::TAU / 12.0;
    q.copy_from_slice(&common::POSE);
    qd.fill(0.0);
    qdd.fill(0.0);
    q[0] += (w * t).sin();
    qd[0] = w * (w * t).cos();
    qdd[0] = -w * w * (w * t).sin();
}
