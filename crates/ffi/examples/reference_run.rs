//! Reference data for the C++ test (tests/cpp/run.sh): the Rust loop ([`RobotLoop::step`],
//! the code `adm_step` wraps, called here with Rust slices and no C ABI) of a deployment
//! folder (`admittance deploy`), fed N periods of a measured motion, writing what went in
//! and what came out:
//!
//! * `inputs.bin`: `"ADMIN001"`, `u32 n`, `u32 steps`, then per step `f64 time`,
//!   `u32 n_joints`, `u32 flags`, and `n` values each of `q`, `qdot`, `tau`, `q_d`,
//!   `qdot_d`, `qddot_d` (little-endian `f64`);
//! * `outputs.bin`: `"ADMOUT02"`, `u32 n`, `u32 steps`, then per step the `AdmOutput`
//!   this program assembled from the Rust loop's results ([`output_of`]), byte for byte.
//!
//! The motion: the arm swinging slowly around its mid-range (16-bit encoder), with the
//! torque its inverse dynamics needs plus a push of 3 N m on the first joint from 20 s to
//! 30 s. The sequence exercises every input flag and the faults: measured torque with the
//! pose held, then a caller's trajectory, then measured velocities with the last command
//! as torque; a NaN burst, one angle of 1e20 and one torque of 1e300 in between.
//!
//! Run: `cargo run --release -p admittance-ffi --example reference_run -- DEPLOY_DIR OUT_DIR [STEPS]`

use std::io::{BufWriter, Write};
use std::path::Path;

use admittance_dynamics::{rnea, Data};
use admittance_ffi::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        return Err("usage: reference_run DEPLOY_DIR OUT_DIR [STEPS]".into());
    }
    let (deploy, out_dir) = (Path::new(&args[1]), Path::new(&args[2]));
    let steps: u32 = args.get(3).map_or(Ok(100_000), |s| s.parse())?;
    let mut rust_loop = RobotLoop::load(deploy, &[])?;
    rust_loop.enable_wrench(0.0)?;
    let n = rust_loop.dof();
    let dt = rust_loop.dt();
    let model = rust_loop.model().clone();
    let mut data = Data::new(&model);
    let centre: Vec<f64> = model
        .joints
        .iter()
        .map(|j| {
            let l = &j.limits;
            if l.lower.is_finite() && l.upper.is_finite() {
                0.5 * (l.lower + l.upper)
            } else {
                0.0
            }
        })
        .collect();

    std::fs::create_dir_all(out_dir)?;
    let mut inputs = BufWriter::new(std::fs::File::create(out_dir.join("inputs.bin"))?);
    let mut outputs = BufWriter::new(std::fs::File::create(out_dir.join("outputs.bin"))?);
    for (w, magic) in [(&mut inputs, b"ADMIN001"), (&mut outputs, b"ADMOUT02")] {
        w.write_all(magic)?;
        w.write_all(&(n as u32).to_le_bytes())?;
        w.write_all(&steps.to_le_bytes())?;
    }
    let resolution = std::f64::consts::TAU / 65536.0;
    let (mut q, mut qdot, mut qddot, mut tau) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut q_d, mut qdot_d, mut qddot_d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut faults = 0;
    for k in 0..steps {
        let time = k as f64 * dt;
        for i in 0..n {
            let w = std::f64::consts::TAU / (12.0 + 3.0 * i as f64);
            q[i] = centre[i] + 0.2 * (w * time).sin();
            qdot[i] = 0.2 * w * (w * time).cos();
            qddot[i] = -0.2 * w * w * (w * time).sin();
        }
        let inverse = rnea(&model, &mut data, &q, &qdot, &qddot)?;
        tau.copy_from_slice(inverse.as_slice());
        if (20.0..30.0).contains(&time) {
            tau[0] -= 3.0;
        }
        for x in q.iter_mut() {
            *x = (*x / resolution).round() * resolution;
        }
        // A NaN burst on joint 2 (3 periods), an absurd angle and an absurd torque.
        if (55_000..55_003).contains(&k) {
            q[2] = f64::NAN;
        }
        if k == 35_000 {
            q[3] = 1e20;
        }
        if k == 36_000 {
            tau[1] = 1e300;
        }
        let flags = match k {
            0..40_000 => ADM_INPUT_TAU,
            40_000..70_000 => {
                // The caller's own trajectory: the measured motion's, slower on joint 1.
                for i in 0..n {
                    let w = std::f64::consts::TAU / (12.0 + 3.0 * i as f64);
                    q_d[i] = centre[i] + 0.2 * (w * time).sin();
                    qdot_d[i] = 0.2 * w * (w * time).cos();
                    qddot_d[i] = -0.2 * w * w * (w * time).sin();
                }
                ADM_INPUT_TAU | ADM_INPUT_DESIRED
            }
            _ => ADM_INPUT_QDOT,
        };
        let has = |bit: u32| flags & bit != 0;
        let status = rust_loop.step(&RobotInput {
            time,
            q: &q,
            qdot: has(ADM_INPUT_QDOT).then_some(&qdot[..]),
            tau: has(ADM_INPUT_TAU).then_some(&tau[..]),
            desired: has(ADM_INPUT_DESIRED).then_some([&q_d[..], &qdot_d[..], &qddot_d[..]]),
        });
        let report = report_of(&status, true);
        faults += (report.fault != ADM_FAULT_NONE) as u32;

        inputs.write_all(&time.to_le_bytes())?;
        inputs.write_all(&(n as u32).to_le_bytes())?;
        inputs.write_all(&flags.to_le_bytes())?;
        for v in [&q, &qdot, &tau, &q_d, &qdot_d, &qddot_d] {
            for x in v.iter() {
                inputs.write_all(&x.to_le_bytes())?;
            }
        }
        let out = output_of(&rust_loop, &report, time, k as u64 + 1);
        // SAFETY: AdmOutput is `#[repr(C)]` plain data without padding (asserted in
        // abi.rs), so its bytes are initialised; the slice lives as long as `out`.
        let bytes = unsafe {
            std::slice::from_raw_parts(
                (&out as *const AdmOutput).cast::<u8>(),
                std::mem::size_of::<AdmOutput>(),
            )
        };
        outputs.write_all(bytes)?;
    }
    inputs.flush()?;
    outputs.flush()?;
    println!(
        "reference_run: {steps} steps of {n} joints ({} s), {faults} with a fault, {} implausible, \
         final q_r[0] = {:.4} rad, tau_ext[0] = {:.3} N m -> {}",
        steps as f64 * dt,
        rust_loop.implausible_samples(),
        rust_loop.reference()[0][0],
        rust_loop.external_torque_estimate()[0],
        out_dir.display()
    );
    Ok(())
}
