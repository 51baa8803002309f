//! The cost of the C ABI: `adm_step` (checks, `catch_unwind`, copying `AdmInput` and
//! `AdmOutput`) against the Rust loop's step it wraps ([`RobotLoop::step`]: signal chain and
//! `ClosedLoop::step` with Rust slices), on the same inputs, for the deployment of scenarios/admittance.toml's
//! variant `momentum` (PD, joint admittance, momentum observer with the 10 Hz input stage,
//! 7 joints) with measured torques. docs/benchmarks.md records the medians.
//!
//! Run: `cargo bench -p admittance-ffi --bench step`

use std::ffi::CString;
use std::hint::black_box;
use std::time::Duration;

use admittance_ffi::*;
use criterion::{criterion_group, criterion_main, Criterion};

#[path = "../tests/common/mod.rs"]
mod common;

const N: usize = 7;

/// One trajectory period (12 s) of inputs: the arm tracking the scenario's desired motion
/// with a small error, with measured torques (index `k` is time `k` ms, so the ring can be
/// cycled with increasing time).
fn inputs() -> Vec<AdmInput> {
    let (mut q_d, mut qd, mut qdd) = ([0.0; N], [0.0; N], [0.0; N]);
    (0..12_000)
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
        .collect()
}

fn bench(c: &mut Criterion) {
    let (_tmp, dir) = common::deploy("momentum");
    let mut rust = RobotLoop::load(&dir, &[]).expect("deployment folder");
    let ring = inputs();
    let mut group = c.benchmark_group("ffi_step");
    let mut k = 0usize;
    group.bench_function("rust_loop_step", |b| {
        b.iter(|| {
            let inp = &ring[k % ring.len()];
            let report = rust.step(&RobotInput {
                time: k as f64 * 1e-3,
                q: black_box(&inp.q[..N]),
                qdot: None,
                tau: Some(black_box(&inp.tau[..N])),
                desired: Some([&inp.q_d[..N], &inp.qdot_d[..N], &inp.qddot_d[..N]]),
            });
            k += 1;
            black_box((report, rust.torque()[0]))
        })
    });

    let path = CString::new(dir.to_str().unwrap()).unwrap();
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
    assert!(!h.is_null(), "adm_create failed");
    let mut out = AdmOutput::ZERO;
    let mut k = 0usize;
    let mut ring = ring;
    let len = ring.len();
    group.bench_function("adm_step", |b| {
        b.iter(|| {
            let inp = &mut ring[k % len];
            inp.time = k as f64 * 1e-3;
            // SAFETY: a live handle, valid input and output.
            let status = unsafe { adm_step(black_box(h), black_box(&*inp), &mut out) };
            k += 1;
            black_box((status, out.tau_cmd[0]))
        })
    });
    group.finish();
    // SAFETY: a live handle, no longer used.
    unsafe { adm_destroy(h) };

    // adm_create on a deployed folder (issue 32: under 100 ms, never trains): reads and
    // verifies every file, loads the URDF, builds the loop; then adm_destroy.
    let mut group = c.benchmark_group("ffi_create");
    group.sample_size(20);
    group.bench_function("adm_create_destroy", |b| {
        b.iter(|| {
            // SAFETY: `config` and its strings outlive the call; the handle is destroyed.
            unsafe {
                let h = adm_create(black_box(&config));
                assert!(!h.is_null());
                adm_destroy(h);
            }
        })
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    targets = bench
}
criterion_main!(benches);

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
