//! The C functions called from Rust: create errors that name the file and key, step
//! statuses, the panic boundary, the error buffer, and `adm_step` against the Rust loop.

use std::ffi::{CStr, CString};
use std::os::raw::c_char;
use std::path::Path;

use admittance_ffi::*;

fn scenario() -> CString {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/admittance.toml"
    );
    CString::new(path).unwrap()
}

fn config(path: &CString, variant: &CString) -> AdmConfig {
    AdmConfig {
        abi_version: ADM_ABI_VERSION,
        n_joints: 7,
        scenario_path: path.as_ptr(),
        variant: variant.as_ptr(),
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

/// Input of period `k`: a slow motion around the scenario's pose.
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
    let (path, variant) = (scenario(), CString::new("momentum").unwrap());
    // SAFETY: null is accepted.
    assert!(unsafe { adm_create(std::ptr::null()) }.is_null());
    assert!(create_error().contains("config is null"));

    let mut c = config(&path, &variant);
    c.abi_version = 99;
    create_fails(&c, &["abi_version is 99"]);

    let mut c = config(&path, &variant);
    c.n_joints = 6;
    create_fails(
        &c,
        &["admittance.toml", "n_joints is 6", "7 joints", "left_s0"],
    );

    let missing = CString::new("no/such/file.toml").unwrap();
    create_fails(&config(&missing, &variant), &["no/such/file.toml"]);

    let oracle = CString::new("oracle").unwrap();
    create_fails(
        &config(&path, &oracle),
        &["admittance.toml", "observer.kind", "oracle"],
    );

    let unknown = CString::new("no_such_variant").unwrap();
    create_fails(&config(&path, &unknown), &["no_such_variant"]);

    let overrides = CString::new("controller.pd.kp = [1.0, 2.0]").unwrap();
    let mut c = config(&path, &variant);
    c.overrides = overrides.as_ptr();
    create_fails(&c, &["controller.pd.kp", "has 2 values", "7 joints"]);

    let mut c = config(&path, &variant);
    c.flags = 1 << 7;
    create_fails(&c, &["AdmConfig.flags"]);
}

#[test]
fn step_statuses_and_errors() {
    let (path, variant) = (scenario(), CString::new("momentum").unwrap());
    let h = create(&config(&path, &variant));
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
    let (path, variant) = (scenario(), CString::new("momentum").unwrap());
    let h = create(&config(&path, &variant));
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
    let (path, variant) = (scenario(), CString::new("momentum").unwrap());
    let h = create(&config(&path, &variant));
    let path = Path::new(path.to_str().unwrap());
    let mut rust = RustLoop::new(&LoopSettings {
        scenario: path,
        variant: Some("momentum"),
        overrides: Vec::new(),
        wrench_damping: Some(0.0),
    })
    .unwrap();
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
        let report = rust.step(&StepInput {
            time: inp.time,
            q: &inp.q[..7],
            qdot: has(ADM_INPUT_QDOT).then_some(&inp.qdot[..7]),
            tau: has(ADM_INPUT_TAU).then_some(&inp.tau[..7]),
            desired: has(ADM_INPUT_DESIRED).then_some([
                &inp.q_d[..7],
                &inp.qdot_d[..7],
                &inp.qddot_d[..7],
            ]),
        });
        assert_eq!(status == ADM_FAULT, report.fault != ADM_FAULT_NONE);
        assert_eq!((out.flags, out.fault), (report.flags, report.fault));
        let bits = |s: &[f64]| s.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&out.tau_cmd[..7]), bits(rust.torque()), "step {k}");
        assert_eq!(
            bits(&out.tau_ext[..7]),
            bits(rust.external_torque_estimate())
        );
        assert_eq!(bits(&out.q_r[..7]), bits(rust.reference()[0]));
        assert_eq!(bits(&out.wrench), bits(rust.wrench().unwrap().0));
    }
    // SAFETY: a live handle.
    unsafe { adm_destroy(h) };
}
