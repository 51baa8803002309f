//! The CSV: its layout, exact numbers, atomic writing, and refusing files it did not write.

mod common;

use admittance_bag::{import, import_to_csv, BagError, ImportOptions, Profile, STAMP_COLUMN};
use common::*;

fn franka() -> Profile {
    Profile::builtin("franka").unwrap().unwrap()
}

#[test]
fn csv_has_the_free_motion_layout_and_exact_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("free.csv");
    let options = ImportOptions::default();
    let report = import_to_csv(&data("franka_plain.mcap"), &franka(), &options, &out).unwrap();
    let table = import(&data("franka_plain.mcap"), &franka(), &options)
        .unwrap()
        .table;
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let j: Vec<String> = (1..=7).map(|i| format!("fr3_joint{i}")).collect();
    let mut expected = vec!["t".to_string()];
    for p in ["q", "qdot", "qddot", "tau", "label"] {
        expected.extend(j.iter().map(|j| format!("{p}.{j}")));
    }
    expected.push(STAMP_COLUMN.into());
    assert_eq!(header, expected);
    let lines: Vec<&str> = lines.collect();
    let rows: Vec<Vec<f64>> = lines
        .iter()
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), report.rows);
    assert_eq!(rows.len(), table.len());
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r.len(), header.len());
        assert_eq!(r[0], table.t[k]);
        assert_eq!(&r[1..8], &table.q[k * 7..k * 7 + 7]);
        assert_eq!(&r[15..22], &table.qddot[k * 7..k * 7 + 7]);
        assert_eq!(&r[22..29], &table.tau[k * 7..k * 7 + 7]);
        let stamp: i64 = lines[k].rsplit(',').next().unwrap().parse().unwrap();
        assert_eq!(stamp, table.stamps_ns[k]);
    }
    assert_eq!(rows[0][0], 0.0);
}

#[test]
fn out_replaces_only_its_own_csv_and_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let bag = data("franka_plain.mcap");
    let options = ImportOptions::default();
    let out = dir.path().join("free.csv");
    import_to_csv(&bag, &franka(), &options, &out).unwrap();
    let first = std::fs::read(&out).unwrap();
    // Its own file: replaced (here with the same content).
    import_to_csv(&bag, &franka(), &options, &out).unwrap();
    assert_eq!(std::fs::read(&out).unwrap(), first);
    // A user's file, a folder, a missing folder: refused before any work, untouched.
    let user = dir.path().join("user.csv");
    std::fs::write(&user, "t,q.a,qdot.a,qddot.a,tau.a\n0,1,2,3,4\n").unwrap();
    let e = import_to_csv(&bag, &franka(), &options, &user).unwrap_err();
    assert!(matches!(e, BagError::Destination { .. }), "{e}");
    assert!(
        e.to_string().contains("user.csv") && e.to_string().contains("refusing to replace"),
        "{e}"
    );
    assert_eq!(
        std::fs::read_to_string(&user).unwrap(),
        "t,q.a,qdot.a,qddot.a,tau.a\n0,1,2,3,4\n"
    );
    let e = import_to_csv(&bag, &franka(), &options, dir.path()).unwrap_err();
    assert!(e.to_string().contains("not a regular file"), "{e}");
    let e =
        import_to_csv(&bag, &franka(), &options, &dir.path().join("no/such/x.csv")).unwrap_err();
    assert!(e.to_string().contains("its folder"), "{e}");
    // A bad bag leaves the destination as it was.
    let e = import_to_csv(&data("franka_sqlite"), &franka(), &options, &out).unwrap_err();
    assert!(matches!(e, BagError::Sqlite { .. }));
    assert_eq!(std::fs::read(&out).unwrap(), first);
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    assert!(names.iter().all(|n| !n.contains(".tmp")), "{names:?}");
}

#[test]
fn report_lists_topics_counts_skips_rate_and_duration() {
    let im = import(&data("franka_zstd"), &franka(), &ImportOptions::default()).unwrap();
    let text = im.report.to_string();
    for part in [
        "/franka_robot_state_broadcaster/measured_joint_states (sensor_msgs/msg/JointState): 1000 messages",
        "/franka_robot_state_broadcaster/external_wrench_in_base_frame (geometry_msgs/msg/WrenchStamped): 250 messages",
        "skipped messages: 0",
        "rate: 1000.000000 Hz (the median rate of the q topic)",
        "rows: 995 (0.994 s; 1 leading rows dropped",
        "time: message stamps",
    ] {
        assert!(text.contains(part), "{part} not in\n{text}");
    }
}
