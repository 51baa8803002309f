//! Bags written by `rosbags` (tests/make_bags.py) from an analytic trajectory, imported
//! with each profile, compared with the truth.
//!
//! Tolerances: at the bag's own rate the grid is the message stamps, so q, qdot and tau
//! are the recorded values (1e-9); qddot is the backward difference of the recorded qdot
//! (compared with the difference of the true qdot, 1e-9, and with the true qddot within
//! the difference's O(dt) error). Interpolated columns (labels at another rate, any column
//! at `rate != 1 kHz`) are compared within the linear-interpolation bound h^2/8 max|f''|.

mod common;

use admittance_bag::{import, BagError, ImportOptions, Imported, Profile};
use common::*;

fn run(bag: &str, profile: &Profile, rate: Option<f64>) -> Imported {
    let options = ImportOptions {
        rate_hz: rate,
        accept_damage: false,
        ..Default::default()
    };
    import(&data(bag), profile, &options).unwrap_or_else(|e| panic!("{bag}: {e}"))
}

fn builtin(name: &str) -> Profile {
    Profile::builtin(name).unwrap().unwrap()
}

/// Largest errors of (q, qdot, tau) against the truth, per table.
fn state_errors(im: &Imported) -> (f64, f64, f64) {
    let t = &im.table;
    let n = t.joints.len();
    let truth_at = |f: fn((f64, f64, f64, f64)) -> f64| {
        t.stamps_ns
            .iter()
            .flat_map(move |s| (0..n).map(move |i| f(truth(i, secs(*s)))))
            .collect::<Vec<_>>()
    };
    (
        max_err(t.q.iter().copied(), truth_at(|r| r.0)),
        max_err(t.qdot.iter().copied(), truth_at(|r| r.1)),
        max_err(t.tau.iter().copied(), truth_at(|r| r.3)),
    )
}

#[test]
fn franka_zstd_folder_at_its_own_rate_is_the_recorded_samples() {
    let im = run("franka_zstd", &builtin("franka"), None);
    let t = &im.table;
    assert_eq!(im.report.rate_hz, 1000.0);
    assert!(im.report.rate_is_median);
    assert_eq!(
        t.joints,
        (1..=7).map(|i| format!("fr3_joint{i}")).collect::<Vec<_>>()
    );
    // Labels at 250 Hz from 0.5 ms to 996.5 ms: the grid is the q stamps from 1 ms
    // (anchored on q) to 996 ms, minus the first row (no qddot yet).
    assert_eq!(t.stamps_ns[0], T0_NS + 2_000_000);
    assert_eq!(*t.stamps_ns.last().unwrap(), T0_NS + 996_000_000);
    assert_eq!(t.len(), 995);
    assert_eq!(t.t[1], 0.001);
    let (eq, eqd, etau) = state_errors(&im);
    assert!(eq < 1e-9 && eqd < 1e-9 && etau < 1e-9, "{eq} {eqd} {etau}");
    // qddot: the backward difference of qdot, exactly; vs the true qddot within
    // dt/2 max|q'''| = 0.0005 * 0.6 * (2 pi 1.1)^3 ~ 0.099.
    let (mut e_diff, mut e_true) = (0.0f64, 0.0f64);
    for (k, s) in t.stamps_ns.iter().enumerate() {
        for i in 0..7 {
            let now = truth(i, secs(*s));
            let before = truth(i, secs(s - 1_000_000));
            let x = t.qddot[k * 7 + i];
            e_diff = e_diff.max((x - (now.1 - before.1) / 1e-3).abs());
            e_true = e_true.max((x - now.2).abs());
        }
    }
    assert!(e_diff < 1e-9, "{e_diff}");
    assert!(e_true < 0.1, "{e_true}");
    // The 250 Hz label, interpolated: h^2/8 max|f''| = 16e-6/8 * 1.4 (2 pi)^2 = 1.1e-4.
    let (cols, v) = t.label.as_ref().unwrap();
    assert_eq!(cols.len(), 7);
    let truth_label = t
        .stamps_ns
        .iter()
        .flat_map(|s| (0..7).map(move |i| label(i, secs(*s))));
    let e_label = max_err(v.iter().copied(), truth_label);
    assert!(e_label < 1.2e-4, "{e_label}");
    // Every message read, none skipped, header stamps used.
    assert_eq!(im.report.skipped(), 0);
    let counts: Vec<usize> = im.report.topics.iter().map(|c| c.messages).collect();
    assert_eq!(counts, vec![250, 250, 1000]);
    assert!(im.report.signals.iter().all(|s| s.time.log_time == 0));
    println!("franka zstd: q {eq:e} qdot {eqd:e} tau {etau:e} qddot-diff {e_diff:e} qddot-true {e_true:e} label {e_label:e}");
}

#[test]
fn franka_resampled_at_300_hz_within_the_interpolation_bound() {
    let im = run("franka_zstd", &builtin("franka"), Some(300.0));
    assert!((im.report.rate_hz - 300.0).abs() < 1e-4 && !im.report.rate_is_median);
    assert_eq!(im.table.stamps_ns[1] - im.table.stamps_ns[0], 3_333_333);
    // h = 1 ms: q <= 1.25e-7 * 0.6 (2 pi 1.1)^2 = 3.6e-6; qdot <= 1.25e-7 * 330 = 4.1e-5;
    // tau (5 sin q + ...) <= 1.25e-7 * max|tau''| < 1.25e-7 * 2e3 = 2.5e-4.
    let (eq, eqd, etau) = state_errors(&im);
    assert!(
        eq < 3.6e-6 && eqd < 4.1e-5 && etau < 2.5e-4,
        "{eq} {eqd} {etau}"
    );
    println!("franka 300 Hz: q {eq:e} qdot {eqd:e} tau {etau:e}");
}

#[test]
fn franka_plain_single_file() {
    let im = run("franka_plain.mcap", &builtin("franka"), None);
    let (eq, eqd, etau) = state_errors(&im);
    assert!(eq < 1e-9 && eqd < 1e-9 && etau < 1e-9, "{eq} {eqd} {etau}");
    assert!(im.table.len() >= 90, "{}", im.table.len());
}

#[test]
fn ur_needs_torque_constants_and_maps_joints_by_name() {
    let e = Profile::builtin("ur").unwrap().unwrap_err().to_string();
    assert!(
        e.contains("torque_constant") && e.contains("motor current"),
        "{e}"
    );
    let text = include_str!("../profiles/ur.toml").replace(
        "unit = \"A\"",
        "unit = \"A\"\ntorque_constant = [10.0, 10.0, 10.0, 5.0, 5.0, 5.0]",
    );
    let profile = Profile::parse(&text, "ur-test.toml").unwrap();
    let im = run("ur_plain", &profile, None);
    // The folder's metadata.yaml names the same bag.
    assert_eq!(
        run("ur_plain/metadata.yaml", &profile, None).table,
        im.table
    );
    assert_eq!(im.report.rate_hz, 500.0);
    assert_eq!(im.table.joints[0], "shoulder_pan_joint");
    let (eq, eqd, etau) = state_errors(&im);
    assert!(eq < 1e-9 && eqd < 1e-9 && etau < 1e-9, "{eq} {eqd} {etau}");
    let (cols, v) = im.table.label.as_ref().unwrap();
    assert_eq!(cols, &["fx", "fy", "fz", "tx", "ty", "tz"]);
    let truth_w = im.table.stamps_ns.iter().flat_map(|s| wrench(secs(*s)));
    assert!(max_err(v.iter().copied(), truth_w) < 1e-9);
}

#[test]
fn lbr_state_custom_type_with_its_own_stamp() {
    let im = run("lbr_zstd", &builtin("lbr"), None);
    let t = &im.table;
    assert_eq!(t.joints[6], "lbr_A7");
    assert!(im
        .report
        .signals
        .iter()
        .all(|s| s.time.has_stamp && s.time.log_time == 0));
    // No qdot in LBRState: qdot and qddot are backward differences of q (2 rows dropped).
    assert_eq!(im.report.dropped_leading_rows, 2);
    let (eq, _, etau) = state_errors(&im);
    assert!(eq < 1e-9 && etau < 1e-9, "{eq} {etau}");
    let mut e = 0.0f64;
    for (k, s) in t.stamps_ns.iter().enumerate() {
        for i in 0..7 {
            let q = |d: i64| truth(i, secs(s - d * 1_000_000)).0;
            let qd = (q(0) - q(1)) / 1e-3;
            let qdd = (qd - (q(1) - q(2)) / 1e-3) / 1e-3;
            e = e.max((t.qdot[k * 7 + i] - qd).abs());
            e = e.max((t.qddot[k * 7 + i] - qdd).abs() * 1e-3);
        }
    }
    assert!(e < 1e-9, "{e}");
    let (_, v) = t.label.as_ref().unwrap();
    let truth_label = t
        .stamps_ns
        .iter()
        .flat_map(|s| (0..7).map(move |i| label(i, secs(*s))));
    assert!(max_err(v.iter().copied(), truth_label) < 1e-9);
}

#[test]
fn sqlite_bag_is_refused_with_the_conversion_command() {
    let options = ImportOptions::default();
    for path in ["franka_sqlite", "franka_sqlite/franka_sqlite.db3"] {
        let e = import(&data(path), &builtin("franka"), &options).unwrap_err();
        assert!(matches!(e, BagError::Sqlite { .. }), "{e}");
        let text = e.to_string();
        assert!(
            text.contains("rosbags-convert --src BAG --dst OUT --dst-storage mcap"),
            "{text}"
        );
        assert!(text.contains("franka_sqlite"), "{text}");
    }
}

#[test]
fn float64_multi_array_torques_are_stamped_by_the_log_time_and_say_so() {
    use admittance_bag::msgs::{self, Float64MultiArray, MultiArrayDimension, MultiArrayLayout};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("array.mcap");
    let mut out = Vec::new();
    for k in 0..50i64 {
        let stamp = T0_NS + k * 1_000_000;
        let s = secs(stamp);
        out.push(js_message(
            "/js",
            stamp as u64 + 300_000,
            &joint_state(3, stamp, s),
        ));
        // Torques on their own topic, no header: the log time is their only time. A
        // leading element skipped by data_offset.
        let mut data = vec![99.0];
        // In the profile's joint order (j2, j0, j1): an array is positional.
        data.extend([2, 0, 1].map(|i| -truth(i, s).3));
        let array = Float64MultiArray {
            layout: MultiArrayLayout {
                dim: vec![MultiArrayDimension {
                    label: "joints".into(),
                    size: 3,
                    stride: 3,
                }],
                data_offset: 1,
            },
            data,
        };
        out.push(Out {
            topic: "/tau".into(),
            type_name: "std_msgs/msg/Float64MultiArray".into(),
            log_ns: stamp as u64,
            data: msgs::encode(&array).unwrap(),
        });
    }
    write_mcap(&path, &out);
    let text = "name = \"array\"\ndescription = \"d\"\njoints = [\"j2\", \"j0\", \"j1\"]\n[q]\ntopic = \"/js\"\ntype = \"sensor_msgs/msg/JointState\"\nfield = \"position\"\n[tau]\ntopic = \"/tau\"\ntype = \"std_msgs/msg/Float64MultiArray\"\nfield = \"data\"\n";
    let profile = Profile::parse(text, "array.toml").unwrap();
    let im = import(&path, &profile, &ImportOptions::default()).unwrap();
    let tau = &im.report.signals[1];
    assert_eq!((tau.time.has_stamp, tau.time.log_time), (false, 50));
    assert!(im
        .report
        .to_string()
        .contains("log (receive) time: the type has no stamp"));
    // q by name in the profile's order (j2, j0, j1); the array positionally in that order.
    let t = &im.table;
    for (k, s) in t.stamps_ns.iter().enumerate() {
        let s = secs(*s);
        assert_eq!(t.q[k * 3], truth(2, s).0);
        assert_eq!(t.q[k * 3 + 1], truth(0, s).0);
        for (c, i) in [2usize, 0, 1].iter().enumerate() {
            assert!((t.tau[k * 3 + c] + truth(*i, s).3).abs() < 1e-12);
        }
    }
}

#[test]
fn franka_zstd_single_file_from_the_mcap_package() {
    let im = run("franka_crc_zstd.mcap", &builtin("franka"), None);
    let (eq, eqd, etau) = state_errors(&im);
    assert!(eq < 1e-9 && eqd < 1e-9 && etau < 1e-9, "{eq} {eqd} {etau}");
}
