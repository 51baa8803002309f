//! The `extern "C"` functions. `adm_create` and `adm_destroy` allocate and free (not
//! real-time); `adm_step` allocates nothing, takes no lock, and never lets a panic cross
//! the boundary: it is caught, the last good output is held, a distinct status returned
//! and the message recorded for `adm_last_error`.

use std::cell::RefCell;
use std::ffi::CStr;
use std::os::raw::c_char;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use crate::abi::*;
use crate::engine::{output_of, report_of, RobotInput, RobotLoop};
use crate::error_buf::{copy_to_c, ErrorBuf};

/// An opaque loop: made by `adm_create`, stepped by `adm_step`, freed by `adm_destroy`.
/// One handle is stepped by one thread at a time (it is not synchronised).
pub struct AdmHandle {
    engine: RobotLoop,
    /// `ADM_CONFIG_WRENCH` was set.
    wrench: bool,
    n: usize,
    steps: u64,
    /// The last good output, held after a panic.
    last: AdmOutput,
    poisoned: bool,
    error: ErrorBuf,
    /// Test hook: the next step panics (see [`adm_test_panic_next_step`]).
    panic_next: bool,
}

thread_local! {
    /// Why the last `adm_create` on this thread failed.
    static CREATE_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

fn set_create_error(msg: String) {
    CREATE_ERROR.with(|e| *e.borrow_mut() = msg);
}

/// The version of the ABI the library was built with (`ADM_ABI_VERSION` of its header).
#[no_mangle]
pub extern "C" fn adm_abi_version() -> u32 {
    ADM_ABI_VERSION
}

/// A UTF-8 C string, or `None` for null; `what` names the field in the error.
///
/// # Safety
/// `p` is null or a NUL-terminated string.
unsafe fn c_str<'a>(p: *const c_char, what: &str) -> Result<Option<&'a str>, String> {
    if p.is_null() {
        return Ok(None);
    }
    // SAFETY: non-null, and the caller guarantees NUL termination.
    let s = unsafe { CStr::from_ptr(p) };
    s.to_str()
        .map(Some)
        .map_err(|e| format!("AdmConfig.{what}: not UTF-8 ({e})"))
}

/// Builds the loop of the deployment folder `config.deployment_path` (written by
/// `admittance deploy`: every file checked against its manifest) and allocates all it
/// will use. Not real-time: it reads files; it never trains. Returns null on any error;
/// `adm_last_error(NULL, ...)` on the same thread then names the file and key.
///
/// # Safety
/// `config` is null or points to an `AdmConfig` whose strings are null or NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn adm_create(config: *const AdmConfig) -> *mut AdmHandle {
    // SAFETY: forwarded to `create`, which has the same contract.
    match catch_unwind(|| unsafe { create(config) }) {
        Ok(Ok(handle)) => {
            set_create_error(String::new());
            Box::into_raw(Box::new(handle))
        }
        Ok(Err(msg)) => {
            set_create_error(msg);
            std::ptr::null_mut()
        }
        Err(panic) => {
            set_create_error(format!(
                "adm_create panicked (a bug, please report it): {}",
                panic_message(&*panic)
            ));
            std::ptr::null_mut()
        }
    }
}

/// # Safety
/// As [`adm_create`].
unsafe fn create(config: *const AdmConfig) -> Result<AdmHandle, String> {
    if config.is_null() {
        return Err("adm_create: config is null".into());
    }
    // SAFETY: non-null, and the caller guarantees it points to an AdmConfig.
    let c = unsafe { &*config };
    if c.abi_version != ADM_ABI_VERSION {
        return Err(format!(
            "AdmConfig.abi_version is {}, this library implements ABI {ADM_ABI_VERSION}: \
             rebuild against its admittance.h",
            c.abi_version
        ));
    }
    // SAFETY: the caller guarantees the strings are null or NUL-terminated.
    let (path, overrides) = unsafe {
        (
            c_str(c.deployment_path, "deployment_path")?,
            c_str(c.overrides, "overrides")?,
        )
    };
    let path = path
        .ok_or("AdmConfig.deployment_path is null: name a folder written by `admittance deploy`")?;
    if c.flags & !ADM_CONFIG_WRENCH != 0 {
        return Err(format!("AdmConfig.flags: unknown bits {:#x}", c.flags));
    }
    let dir = Path::new(path);
    // A scenario file is not deployed in memory: that would need the simulator's crates
    // here, and its networks may not be trained yet. Say what to run instead.
    if dir.is_file() && dir.extension().is_some_and(|e| e == "toml") {
        return Err(format!(
            "{path}: is a file, adm_create takes a deployment folder: run \
             `admittance deploy {path} [--variant NAME] --out DIR` and pass DIR"
        ));
    }
    let overrides: Vec<&str> = overrides
        .unwrap_or("")
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    let mut engine = RobotLoop::load(dir, &overrides).map_err(|e| e.text())?;
    let wrench = c.flags & ADM_CONFIG_WRENCH != 0;
    if wrench {
        engine
            .enable_wrench(c.wrench_damping)
            .map_err(|e| e.within("AdmConfig").text())?;
    }
    let n = engine.dof();
    if c.n_joints as usize != n {
        return Err(format!(
            "{path}: AdmConfig.n_joints is {}, the arm's chain has {n} joints ({})",
            c.n_joints,
            engine.joints().join(", ")
        ));
    }
    let mut last = AdmOutput::ZERO;
    last.n_joints = n as u32;
    Ok(AdmHandle {
        engine,
        wrench,
        n,
        steps: 0,
        last,
        poisoned: false,
        error: ErrorBuf::new(),
        panic_next: false,
    })
}

/// One control period: reads `input`, writes every field of `output`. Real-time: no
/// allocation, no lock, no blocking call; a panic inside is caught (`ADM_ERR_PANIC`).
/// Returns `ADM_OK`, `ADM_FAULT` (the safe hold was written: still send it) or a negative
/// `ADM_ERR_*`, after which `output` holds the last good step's output and
/// `adm_last_error(handle, ...)` says why.
///
/// # Safety
/// `handle` is null or from `adm_create` and not destroyed, used by one thread at a time;
/// `input` and `output` are null or valid.
#[no_mangle]
pub unsafe extern "C" fn adm_step(
    handle: *mut AdmHandle,
    input: *const AdmInput,
    output: *mut AdmOutput,
) -> i32 {
    if handle.is_null() || input.is_null() || output.is_null() {
        return ADM_ERR_NULL;
    }
    // SAFETY: all three are non-null; the caller guarantees they are valid and that no
    // other thread uses the handle, so these are the only references.
    let (h, input, output) = unsafe { (&mut *handle, &*input, &mut *output) };
    if h.poisoned {
        *output = h.last;
        output.flags |= ADM_OUT_HELD;
        return ADM_ERR_POISONED;
    }
    if input.n_joints as usize != h.n {
        h.error.set(format_args!(
            "adm_step: AdmInput.n_joints is {}, the handle has {} joints",
            input.n_joints, h.n
        ));
        *output = h.last;
        return ADM_ERR_JOINTS;
    }
    if !input.time.is_finite() {
        h.error.set(format_args!(
            "adm_step: AdmInput.time is {} (must be finite)",
            input.time
        ));
        *output = h.last;
        return ADM_ERR_TIME;
    }
    let result = catch_unwind(AssertUnwindSafe(|| step(h, input, output)));
    match result {
        Ok(status) => {
            h.last = *output;
            status
        }
        Err(panic) => {
            h.poisoned = true;
            h.error.set(format_args!(
                "adm_step panicked at step {} (time {} s), the output is held and the handle \
                 refuses further steps: {}",
                h.steps + 1,
                input.time,
                panic_message(&*panic)
            ));
            *output = h.last;
            output.flags |= ADM_OUT_HELD;
            // The payload is dropped here, outside the real-time contract: a panic is a bug.
            drop(panic);
            ADM_ERR_PANIC
        }
    }
}

/// The step proper, inside `catch_unwind`.
fn step(h: &mut AdmHandle, input: &AdmInput, output: &mut AdmOutput) -> i32 {
    if h.panic_next {
        h.panic_next = false;
        panic!("test panic requested by adm_test_panic_next_step");
    }
    let n = h.n;
    let has = |bit: u32| input.flags & bit != 0;
    let status = h.engine.step(&RobotInput {
        time: input.time,
        q: &input.q[..n],
        qdot: has(ADM_INPUT_QDOT).then(|| &input.qdot[..n]),
        tau: has(ADM_INPUT_TAU).then(|| &input.tau[..n]),
        desired: has(ADM_INPUT_DESIRED)
            .then(|| [&input.q_d[..n], &input.qdot_d[..n], &input.qddot_d[..n]]),
    });
    h.steps += 1;
    let report = report_of(&status, h.wrench);
    *output = output_of(&h.engine, &report, input.time, h.steps);
    if report.fault == ADM_FAULT_NONE {
        ADM_OK
    } else {
        ADM_FAULT
    }
}

/// The text of a panic payload (a `&str` or a `String`; no allocation).
fn panic_message(panic: &(dyn std::any::Any + Send)) -> &str {
    panic
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| panic.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("(a panic without a message)")
}

/// Frees a handle (null is accepted). Not real-time.
///
/// # Safety
/// `handle` is null or from `adm_create`, not yet destroyed, and no longer used.
#[no_mangle]
pub unsafe extern "C" fn adm_destroy(handle: *mut AdmHandle) {
    if !handle.is_null() {
        // SAFETY: from `Box::into_raw` in `adm_create`, destroyed once (caller's contract).
        let handle = unsafe { Box::from_raw(handle) };
        let _ = catch_unwind(AssertUnwindSafe(move || drop(handle)));
    }
}

/// Copies the last error message into `buf` (`len` bytes, NUL-terminated, cut at a
/// character boundary) and returns its full length in bytes without the NUL (0: no error),
/// as `snprintf` does. With a handle: the last failed `adm_step` on it (or its panic);
/// with null: the last failed `adm_create` on the calling thread. `buf` may be null to
/// ask for the length. Does not allocate.
///
/// # Safety
/// `handle` is null or a live handle; `buf` is null or valid for `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn adm_last_error(
    handle: *const AdmHandle,
    buf: *mut c_char,
    len: usize,
) -> usize {
    if handle.is_null() {
        // SAFETY: `buf` as guaranteed by the caller.
        CREATE_ERROR.with(|e| unsafe { copy_to_c(&e.borrow(), buf, len) })
    } else {
        // SAFETY: a live handle (caller's contract), only read here.
        let h = unsafe { &*handle };
        // SAFETY: `buf` as guaranteed by the caller.
        unsafe { copy_to_c(h.error.as_str(), buf, len) }
    }
}

/// The handle's joint count (0 for null).
///
/// # Safety
/// `handle` is null or a live handle.
#[no_mangle]
pub unsafe extern "C" fn adm_n_joints(handle: *const AdmHandle) -> u32 {
    // SAFETY: null or live (caller's contract).
    unsafe { handle.as_ref() }.map_or(0, |h| h.n as u32)
}

/// The control period the loop was built for (s; 1 / `control_rate_hz` of `loop.toml`), 0
/// for null.
///
/// # Safety
/// `handle` is null or a live handle.
#[no_mangle]
pub unsafe extern "C" fn adm_control_period(handle: *const AdmHandle) -> f64 {
    // SAFETY: null or live (caller's contract).
    unsafe { handle.as_ref() }.map_or(0.0, |h| h.engine.dt())
}

/// Copies the name of joint `index` (chain order, as in the URDF) into `buf` like
/// `adm_last_error`; returns its length, or 0 for a null handle or an index out of range.
///
/// # Safety
/// `handle` is null or a live handle; `buf` is null or valid for `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn adm_joint_name(
    handle: *const AdmHandle,
    index: u32,
    buf: *mut c_char,
    len: usize,
) -> usize {
    // SAFETY: null or live (caller's contract).
    let Some(h) = (unsafe { handle.as_ref() }) else {
        return 0;
    };
    match h.engine.joints().get(index as usize) {
        // SAFETY: `buf` as guaranteed by the caller.
        Some(name) => unsafe { copy_to_c(name, buf, len) },
        None => 0,
    }
}

/// Test hook (Rust only, not in the C header): the next `adm_step` on `handle` panics
/// inside the boundary, to test the panic path.
pub fn adm_test_panic_next_step(handle: &mut AdmHandle) {
    handle.panic_next = true;
}
