//! The C functions called from Rust: create errors that name the file and key, step
//! statuses, the panic boundary, the error buffer, `adm_step` against the Rust loop, and
//! one absurd finite sample on every observer (issue 34).

mod common;

use std::ffi::{CStr, CString};
use std::os::raw::c_char;
use std::path::Path;

use admittance_ffi::*;

fn c_path(p: &Path) -> CString {
    CString::new(p.to_str().unwrap()).unwrap()
}

fn config(path: &CString) -> AdmConfig {
    AdmConfig {
        abi_version: ADM_ABI_VERSION,
        n_joints: 7,
        deployment_path: path.as_ptr(),
        overrides: std::ptr::null(),
        flags: ADM_CONFIG_WRENCH,
        reserved: 0,
        wrench_damping: 0.0,
    }
}

fn create_error() -> String {
    let mut buf = [0 as c_char; 2048];
    // SAFETY: `buf` is 2048 bytes.
    unsafe { adm_last_error(std::ptr::null(), buf.as_mut_ptr(), buf.len()) };
    // SAFETY: adm_last_error NUL-terminates within the buffer.
    unsafe { CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

fn handle_error(h: *const AdmHandle) -> String {
    let mut buf = [0 as c_char; 2048];
    // SAFETY: a live handle, `buf` is 2048 bytes.
    unsafe { adm_last_error(h, buf.as_mut_ptr(), buf.len()) };
    // SAFETY: NUL-terminated within the buffer.
    unsafe { CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

/// Creates a handle or fails the test with the library's message.
fn create(c: &AdmConfig) -> *mut AdmHandle {
    // SAFETY: `c` and its strings live through the call.
    let h = unsafe { adm_create(c) };
    assert!(!h.is_null(), "adm_create failed: {}", create_error());
    h
}

/// Expects `adm_create` to fail with a message containing every one of `needles`.
fn create_fails(c: &AdmConfig, needles: &[&str]) {
    // SAFETY: `c` and its strings live through the call.
    let h = unsafe { adm_create(c) };
    assert!(h.is_null(), "adm_create accepted a bad config");
    let msg = create_error();
    for n in needles {
        assert!(msg.contains(n), "error {msg:?} does not mention {n:?}");
    }
}

/// Input of period `k`: a slow motion around the experiment's pose.
fn input(k: usize, n: usize, flags: u32) -> AdmInput {
    let pose = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
    let t = k as f64 * 1e-3;
    let mut inp = AdmInput::ZERO;
    inp.time = t;
    inp.n_joints = n as u32;
    inp.flags = flags;
    for (i, &p) in pose.iter().enumerate().take(n) {
        inp.q[i] = p + 0.05 * (t * (1.0 + i as f64)).sin();
        inp.qdot[i] = 0.05 * (1.0 + i as f64) * (t * (1.0 + i as f64)).cos();
        inp.tau[i] = 0.5 * (t * 3.0).sin();
        inp.q_d[i] = p;
    }
    inp
}

#[test]
fn create_errors_name_what_is_wrong() {
    let (_tmp, dir) = common::deploy("momentum");
    let path = c_path(&dir);
    // SAFETY: null is accepted.
    assert!(unsafe { adm_create(std::ptr::null()) }.is_null());
    assert!(create_error().contains("config is null"));

    let mut c = config(&path);
    c.abi_version = 99;
    create_fails(&c, &["abi_version is 99"]);

    let mut c = config(&path);
    c.n_joints = 6;
    create_fails(
        &c,
        &["deploy_momentum", "n_joints is 6", "7 joints", "left_s0"],
    );

    let missing = CString::new("no/such/folder").unwrap();
    create_fails(
        &config(&missing),
        &["no/such/folder", "admittance deploy", "manifest.json"],
    );

    // A scenario file is refused with the command that deploys it.
    let scenario = CString::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/admittance.toml"
    ))
    .unwrap();
    create_fails(
        &config(&scenario),
        &["admittance.toml", "admittance deploy"],
    );

    let overrides = CString::new("controller.pd.kp = [1.0, 2.0]").unwrap();
    let mut c = config(&path);
    c.overrides = overrides.as_ptr();
    create_fails(
        &c,
        &[
            "loop.toml",
            "controller.pd",
            "kp",
            "has 2 values",
            "7 joints",
        ],
    );
    // The very text of the loop's own error: one shape, one text (issue 32, item 5).
    let text = admittance_loop::RobotLoop::load(&dir, &["controller.pd.kp = [1.0, 2.0]"])
        .err()
        .unwrap()
        .text();
    assert_eq!(create_error(), text);

    let mut c = config(&path);
    c.wrench_damping = -1.0;
    create_fails(
        &c,
        &["key `AdmConfig.wrench_damping`: must be finite and >= 0"],
    );

    let overrides = CString::new("observer.kind = \"oracle\"").unwrap();
    let mut c = config(&path);
    c.overrides = overrides.as_ptr();
    create_fails(&c, &["observer.kind", "oracle"]);

    let mut c = config(&path);
    c.flags = 1 << 7;
    create_fails(&c, &["AdmConfig.flags"]);

    // An edited file fails its manifest; a missing one is named.
    let urdf = dir.join("arm.urdf");
    let mut text = std::fs::read_to_string(&urdf).unwrap();
    text.push_str("<!-- edited -->\n");
    std::fs::write(&urdf, text).unwrap();
    create_fails(&config(&path), &["arm.urdf", "does not match the manifest"]);
    std::fs::remove_file(&urdf).unwrap();
    create_fails(&config(&path), &["arm.urdf", "cannot be read"]);

    // A learned observer's network is refused when missing from the folder.
    let (_tmp2, learned) = common::deploy("learned");
    std::fs::remove_file(learned.join("observer.broad")).unwrap();
    create_fails(&config(&c_path(&learned)), &["observer.broad"]);
}

#[test]
fn step_statuses_and_errors() {
    let (_tmp, dir) = common::deploy("momentum");
    let h = create(&config(&c_path(&dir)));
    // SAFETY: a live handle.
    unsafe {
        assert_eq!(adm_n_joints(h), 7);
        assert!((adm_control_period(h) - 1e-3).abs() < 1e-15);
        let mut name = [0 as c_char; 16];
        assert_eq!(adm_joint_name(h, 0, name.as_mut_ptr(), name.len()), 7);
        assert_eq!(CStr::from_ptr(name.as_ptr()).to_str().unwrap(), "left_s0");
        assert_eq!(adm_joint_name(h, 7, name.as_mut_ptr(), name.len()), 0);
    }
    let mut out = AdmOutput::ZERO;
    for k in 0..600 {
        // SAFETY: a live handle and valid pointers.
        let status = unsafe { adm_step(h, &input(k, 7, ADM_INPUT_TAU), &mut out) };
        assert_eq!(status, ADM_OK, "step {k}: {}", handle_error(h));
    }
    assert_eq!(out.step, 600);
    assert_eq!(out.n_joints, 7);
    assert!(out.flags & ADM_OUT_WRENCH != 0);
    assert!(out.tau_cmd[..7].iter().all(|x| x.is_finite()));
    assert!(out.tau_cmd[7..].iter().all(|&x| x == 0.0));
    let good = out;

    // Wrong joint count, non-finite time, null pointers: the output holds the last step's.
    let mut held = AdmOutput::ZERO;
    // SAFETY: valid pointers (or null on purpose).
    unsafe {
        assert_eq!(adm_step(h, &input(600, 6, 0), &mut held), ADM_ERR_JOINTS);
        assert_eq!(held, good);
        assert!(handle_error(h).contains("n_joints is 6"));
        let mut bad_time = input(600, 7, 0);
        bad_time.time = f64::NAN;
        assert_eq!(adm_step(h, &bad_time, &mut held), ADM_ERR_TIME);
        assert!(handle_error(h).contains("time is NaN"));
        assert_eq!(
            adm_step(std::ptr::null_mut(), &bad_time, &mut held),
            ADM_ERR_NULL
        );
        assert_eq!(adm_step(h, std::ptr::null(), &mut held), ADM_ERR_NULL);
        assert_eq!(adm_step(h, &bad_time, std::ptr::null_mut()), ADM_ERR_NULL);
    }

    // A NaN angle: the controller's safe hold, reported as a fault on that joint.
    let mut nan = input(600, 7, ADM_INPUT_TAU);
    nan.q[3] = f64::NAN;
    // SAFETY: valid pointers.
    let status = unsafe { adm_step(h, &nan, &mut out) };
    assert_eq!(status, ADM_FAULT);
    assert_eq!(out.fault, ADM_FAULT_NONFINITE_MEASUREMENT);
    assert_eq!(out.fault_joint, 3);
    assert!(out.flags & (ADM_OUT_CONTROLLER_FAULT | ADM_OUT_NONFINITE_INPUT) != 0);
    assert!(out.tau_cmd[..7].iter().all(|x| x.is_finite()));

    // The error buffer: the full length is returned, the copy is cut and NUL-terminated.
    let mut small = [1 as c_char; 8];
    // SAFETY: `small` is 8 bytes; a null buffer only asks for the length.
    unsafe {
        let full = adm_last_error(h, std::ptr::null_mut(), 0);
        assert!(full > 8);
        assert_eq!(adm_last_error(h, small.as_mut_ptr(), small.len()), full);
        assert_eq!(small[7], 0);
        adm_destroy(h);
        adm_destroy(std::ptr::null_mut());
    }
}

#[test]
fn a_panic_is_caught_the_output_held_and_the_handle_poisoned() {
    let (_tmp, dir) = common::deploy("momentum");
    let h = create(&config(&c_path(&dir)));
    let mut out = AdmOutput::ZERO;
    for k in 0..100 {
        // SAFETY: valid pointers.
        assert_eq!(unsafe { adm_step(h, &input(k, 7, 0), &mut out) }, ADM_OK);
    }
    let good = out;
    // SAFETY: a live handle, not used elsewhere.
    adm_test_panic_next_step(unsafe { &mut *h });
    let mut held = AdmOutput::ZERO;
    // SAFETY: valid pointers.
    assert_eq!(
        unsafe { adm_step(h, &input(100, 7, 0), &mut held) },
        ADM_ERR_PANIC
    );
    assert_eq!(held.flags, good.flags | ADM_OUT_HELD);
    assert_eq!(held.tau_cmd, good.tau_cmd);
    assert_eq!(held.step, good.step);
    let msg = handle_error(h);
    assert!(
        msg.contains("panicked at step 101") && msg.contains("test panic"),
        "{msg}"
    );
    // SAFETY: valid pointers.
    assert_eq!(
        unsafe { adm_step(h, &input(101, 7, 0), &mut held) },
        ADM_ERR_POISONED
    );
    assert_eq!(held.tau_cmd, good.tau_cmd);
    // SAFETY: a live handle.
    unsafe { adm_destroy(h) };
}

/// `adm_step` gives the Rust loop's results bit for bit, for every input flag.
#[test]
fn the_c_step_equals_the_rust_step() {
    let (_tmp, dir) = common::deploy("momentum");
    let h = create(&config(&c_path(&dir)));
    let mut rust = RobotLoop::load(&dir, &[]).unwrap();
    rust.enable_wrench(0.0).unwrap();
    let mut out = AdmOutput::ZERO;
    let flag_sets = [
        0,
        ADM_INPUT_TAU,
        ADM_INPUT_QDOT | ADM_INPUT_DESIRED,
        ADM_INPUT_TAU | ADM_INPUT_QDOT | ADM_INPUT_DESIRED,
    ];
    for k in 0..2000 {
        let inp = input(k, 7, flag_sets[(k / 500) % 4]);
        // SAFETY: valid pointers.
        let status = unsafe { adm_step(h, &inp, &mut out) };
        let has = |bit: u32| inp.flags & bit != 0;
        let report = report_of(
            &rust.step(&RobotInput {
                time: inp.time,
                q: &inp.q[..7],
                qdot: has(ADM_INPUT_QDOT).then_some(&inp.qdot[..7]),
                tau: has(ADM_INPUT_TAU).then_some(&inp.tau[..7]),
                desired: has(ADM_INPUT_DESIRED).then_some([
                    &inp.q_d[..7],
                    &inp.qdot_d[..7],
                    &inp.qddot_d[..7],
                ]),
            }),
            true,
        );
        assert_eq!(status == ADM_FAULT, report.fault != ADM_FAULT_NONE);
        let expected = output_of(&rust, &report, inp.time, k as u64 + 1);
        let bits = |o: &AdmOutput| {
            // SAFETY: AdmOutput is plain data without padding (asserted in abi.rs).
            unsafe {
                std::slice::from_raw_parts(
                    (o as *const AdmOutput).cast::<u8>(),
                    std::mem::size_of::<AdmOutput>(),
                )
            }
            .to_vec()
        };
        assert_eq!(bits(&out), bits(&expected), "step {k}");
    }
    // SAFETY: a live handle.
    unsafe { adm_destroy(h) };
}

/// Safe by default (issue 32): before every joint has an angle the command is zero and the
/// flag says why; without a desired motion the first measured pose is held.
#[test]
fn no_command_before_an_angle_and_the_first_pose_is_held() {
    let (_tmp, dir) = common::deploy("momentum");
    let h = create(&config(&c_path(&dir)));
    let mut out = AdmOutput::ZERO;
    let mut inp = input(0, 7, ADM_INPUT_TAU);
    inp.q[5] = f64::NAN;
    // SAFETY: valid pointers.
    assert_eq!(unsafe { adm_step(h, &inp, &mut out) }, ADM_FAULT);
    assert_eq!(out.fault, ADM_FAULT_NO_ANGLE_YET);
    assert!(out.flags & ADM_OUT_WAITING_FOR_ANGLES != 0);
    assert!(out.tau_cmd.iter().all(|&t| t == 0.0));
    let first = input(1, 7, ADM_INPUT_TAU);
    for k in 1..300 {
        let mut inp = first;
        inp.time = k as f64 * 1e-3;
        // SAFETY: valid pointers.
        assert_eq!(unsafe { adm_step(h, &inp, &mut out) }, ADM_OK, "step {k}");
    }
    assert!(out.flags & ADM_OUT_HOLDING_POSE != 0);
    assert!(out.tau_cmd[..7].iter().any(|&t| t != 0.0));
    for i in 0..7 {
        assert!(
            (out.q_r[i] - first.q[i]).abs() < 1e-9,
            "joint {i}: {} vs {}",
            out.q_r[i],
            first.q[i]
        );
    }
    // SAFETY: a live handle.
    unsafe { adm_destroy(h) };
}

/// Issue 34: one torque of 1e300 and one angle of 1e20 through the C ABI, on every observer:
/// flagged, counted, the command finite, and the estimate back on the clean run's within
/// 1 s. With the gates off the same samples poison the estimate (the test can fail).
#[test]
fn one_absurd_sample_is_flagged_and_forgotten_on_every_observer() {
    let model = common::model();
    let mut data = admittance_dynamics::Data::new(&model);
    let steps = 3000;
    let inputs: Vec<AdmInput> = (0..steps)
        .map(|k| {
            let (q, tau) = common::motion(&model, &mut data, k);
            let mut inp = AdmInput::ZERO;
            inp.time = k as f64 * 1e-3;
            inp.n_joints = 7;
            inp.flags = ADM_INPUT_TAU;
            inp.q[..7].copy_from_slice(&q);
            inp.tau[..7].copy_from_slice(&tau);
            inp
        })
        .collect();
    let (torque_at, angle_at) = (1000, 1500);
    let run = |dir: &Path, overrides: &str, absurd: bool| -> Vec<AdmOutput> {
        let path = c_path(dir);
        let overrides = CString::new(overrides).unwrap();
        let mut c = config(&path);
        c.overrides = overrides.as_ptr();
        let h = create(&c);
        let mut outs = Vec::with_capacity(steps);
        for (k, inp) in inputs.iter().enumerate() {
            let mut inp = *inp;
            if absurd && k == torque_at {
                inp.tau[1] = 1e300;
            }
            if absurd && k == angle_at {
                inp.q[3] = 1e20;
            }
            let mut out = AdmOutput::ZERO;
            // SAFETY: valid pointers.
            unsafe { adm_step(h, &inp, &mut out) };
            outs.push(out);
        }
        // SAFETY: a live handle.
        unsafe { adm_destroy(h) };
        outs
    };
    let gap = |a: &AdmOutput, b: &AdmOutput| {
        (0..7)
            .map(|i| (a.tau_ext[i] - b.tau_ext[i]).abs())
            .fold(0.0, f64::max)
    };
    for kind in ["momentum", "learned", "hybrid"] {
        let (_tmp, dir) = common::deploy(kind);
        let clean = run(&dir, "", false);
        let hit = run(&dir, "", true);
        for (k, flagged) in [(torque_at, 1), (angle_at, 2)] {
            let o = &hit[k];
            assert!(o.flags & ADM_OUT_IMPLAUSIBLE_INPUT != 0, "{kind} step {k}");
            assert_eq!(
                o.fault, ADM_FAULT_IMPLAUSIBLE_MEASUREMENT,
                "{kind} step {k}"
            );
            assert_eq!(o.implausible_samples, flagged, "{kind} step {k}");
        }
        let mut worst_after = 0.0f64;
        let mut worst_during = 0.0f64;
        for k in torque_at..steps {
            let o = &hit[k];
            assert!(
                o.tau_cmd[..7].iter().all(|t| t.is_finite()),
                "{kind} step {k}"
            );
            let g = gap(o, &clean[k]);
            worst_during = worst_during.max(g);
            if k >= angle_at + 1000 {
                worst_after = worst_after.max(g);
            }
        }
        eprintln!("{kind}: estimate off the clean run by at most {worst_during:.3e} N m, {worst_after:.3e} N m 1 s after");
        assert!(worst_during < 1.0, "{kind}: {worst_during} N m");
        assert!(worst_after < 1e-3, "{kind}: {worst_after} N m 1 s after");
        // Without the gates, the same samples poison the estimate.
        let open = run(&dir, "signals.gates.enabled = false", true);
        let poisoned = (torque_at..steps)
            .map(|k| gap(&open[k], &clean[k]))
            .fold(0.0, f64::max);
        assert!(
            poisoned > 1e3 || poisoned.is_nan(),
            "{kind}: ungated gap {poisoned}"
        );
    }
}
