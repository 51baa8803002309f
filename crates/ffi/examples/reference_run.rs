//! Reference data for the C++ test (tests/cpp/run.sh): the Rust loop ([`RustLoop::step`],
//! the code `adm_step` wraps, called here with Rust slices and no C ABI) closed around the
//! project's simulated arm for N periods, writing what went in and what came out:
//!
//! * `inputs.bin`: `"ADMIN001"`, `u32 n`, `u32 steps`, then per step `f64 time`,
//!   `u32 n_joints`, `u32 flags`, and `n` values each of `q`, `qdot`, `tau`, `q_d`,
//!   `qdot_d`, `qddot_d` (little-endian `f64`);
//! * `outputs.bin`: `"ADMOUT01"`, `u32 n`, `u32 steps`, then per step the `AdmOutput`
//!   this program assembled from the Rust loop's results, byte for byte.
//!
//! The C++ test replays `inputs.bin` through `adm_step` and compares each `AdmOutput` with
//! `memcmp`. The sequence exercises every input flag: measured torque with the scenario's
//! trajectory, then a caller's trajectory, then measured velocities with the last command
//! as torque; a NaN burst in between (controller faults, the safe hold).
//!
//! Run: `cargo run --release -p admittance-ffi --example reference_run -- SCENARIO VARIANT OUT_DIR [STEPS]`

use std::io::{BufWriter, Write};
use std::path::Path;

use admittance_ffi::*;
use admittance_sim::Plant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        return Err("usage: reference_run SCENARIO VARIANT OUT_DIR [STEPS]".into());
    }
    let (scenario, variant, out_dir) = (&args[1], &args[2], Path::new(&args[3]));
    let steps: u32 = args.get(4).map_or(Ok(100_000), |s| s.parse())?;
    let mut rust_loop = RustLoop::new(&LoopSettings {
        scenario: Path::new(scenario),
        variant: Some(variant.as_str()),
        overrides: Vec::new(),
        wrench_damping: Some(0.0),
    })?;
    let n = rust_loop.dof();
    let dt = rust_loop.dt();
    let mut plant_config = rust_loop.plant_config().clone();
    let (mut q_d, mut qdot_d, mut qddot_d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    rust_loop.desired_at(0.0, &mut q_d, &mut qdot_d, &mut qddot_d);
    if plant_config.initial_q.is_empty() {
        plant_config.initial_q = q_d.clone();
    }
    let mut plant = Plant::new(rust_loop.model(), &plant_config)?;

    std::fs::create_dir_all(out_dir)?;
    let mut inputs = BufWriter::new(std::fs::File::create(out_dir.join("inputs.bin"))?);
    let mut outputs = BufWriter::new(std::fs::File::create(out_dir.join("outputs.bin"))?);
    for (w, magic) in [(&mut inputs, b"ADMIN001"), (&mut outputs, b"ADMOUT01")] {
        w.write_all(magic)?;
        w.write_all(&(n as u32).to_le_bytes())?;
        w.write_all(&steps.to_le_bytes())?;
    }
    // Encoder resolution of 2^16 counts per revolution.
    let resolution = std::f64::consts::TAU / 65536.0;
    let (mut q, mut qdot, mut tau) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut faults = 0;
    for k in 0..steps {
        let time = k as f64 * dt;
        for i in 0..n {
            q[i] = (plant.q()[i] / resolution).round() * resolution;
            qdot[i] = plant.qdot()[i];
            tau[i] = rust_loop.torque()[i];
        }
        // A NaN burst on joint 2: the controller's safe hold for 3 periods.
        if (55_000..55_003).contains(&k) {
            q[2] = f64::NAN;
        }
        let flags = match k {
            0..40_000 => ADM_INPUT_TAU,
            40_000..70_000 => {
                // The caller's own trajectory: the scenario's plus a slow sine on joint 1.
                rust_loop.desired_at(time, &mut q_d, &mut qdot_d, &mut qddot_d);
                let w = std::f64::consts::TAU / 8.0;
                q_d[1] += 0.05 * (w * time).sin();
                qdot_d[1] += 0.05 * w * (w * time).cos();
                qddot_d[1] -= 0.05 * w * w * (w * time).sin();
                ADM_INPUT_TAU | ADM_INPUT_DESIRED
            }
            _ => ADM_INPUT_QDOT,
        };
        let has = |bit: u32| flags & bit != 0;
        let report = rust_loop.step(&StepInput {
            time,
            q: &q,
            qdot: has(ADM_INPUT_QDOT).then_some(&qdot[..]),
            tau: has(ADM_INPUT_TAU).then_some(&tau[..]),
            desired: has(ADM_INPUT_DESIRED).then_some([&q_d[..], &qdot_d[..], &qddot_d[..]]),
        });
        faults += (report.fault != ADM_FAULT_NONE) as u32;

        inputs.write_all(&time.to_le_bytes())?;
        inputs.write_all(&(n as u32).to_le_bytes())?;
        inputs.write_all(&flags.to_le_bytes())?;
        for v in [&q, &qdot, &tau, &q_d, &qdot_d, &qddot_d] {
            for x in v.iter() {
                inputs.write_all(&x.to_le_bytes())?;
            }
        }
        let mut out = AdmOutput::ZERO;
        out.time = time;
        out.step = k as u64 + 1;
        out.n_joints = n as u32;
        out.flags = report.flags;
        out.fault = report.fault;
        out.fault_joint = report.fault_joint;
        out.tau_cmd[..n].copy_from_slice(rust_loop.torque());
        out.tau_ext[..n].copy_from_slice(rust_loop.external_torque_estimate());
        let [q_r, qdot_r, qddot_r] = rust_loop.reference();
        out.q_r[..n].copy_from_slice(q_r);
        out.qdot_r[..n].copy_from_slice(qdot_r);
        out.qddot_r[..n].copy_from_slice(qddot_r);
        if let Some((base, tip)) = rust_loop.wrench() {
            out.wrench.copy_from_slice(base);
            out.wrench_tip.copy_from_slice(tip);
        }
        // SAFETY: AdmOutput is `#[repr(C)]` plain data without padding (asserted in
        // abi.rs), so its bytes are initialised; the slice lives as long as `out`.
        let bytes = unsafe {
            std::slice::from_raw_parts(
                (&out as *const AdmOutput).cast::<u8>(),
                std::mem::size_of::<AdmOutput>(),
            )
        };
        outputs.write_all(bytes)?;

        plant.step_control(rust_loop.torque())?;
    }
    inputs.flush()?;
    outputs.flush()?;
    println!(
        "reference_run: {steps} steps of {n} joints ({} s), {faults} with a controller fault, \
         final q_r[0] = {:.4} rad, tau_ext[0] = {:.3} N m -> {}",
        steps as f64 * dt,
        rust_loop.reference()[0][0],
        rust_loop.external_torque_estimate()[0],
        out_dir.display()
    );
    Ok(())
}
