//! On the real Baxter recording (`ADMITTANCE_DATA`): fitted on its first 60 s, the shoulder's
//! gravity-assist spring continues along its tangent beyond the positions trained on, and on
//! the last 30 s, where `s1` goes 1.2 rad below them, that holds the false torque far below
//! the Fourier series' own continuation (docs/experiments.md, "Springs continue along their
//! tangent").

use admittance_learning::broad::fnv1a64;
use serde_json::Value;

use crate::identify_cli::{admittance, baxter_recording, identify_baxter, root, row, text};

/// The file's checksum: FNV-1a 64 of the payload's JSON text (docs/outputs.md,
/// "Identification files").
fn checksum(payload: &Value) -> String {
    format!("{:016x}", fnv1a64(payload.to_string().as_bytes()))
}

#[test]
fn the_real_shoulder_spring_continues_along_its_tangent() {
    let Some(data) = baxter_recording() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let tangent = tmp.path().join("tangent.ident.json");
    let (printed, mut file) = identify_baxter(&data, "60", &[], &tangent);
    let s1 = printed
        .lines()
        .find(|l| l.trim_start().starts_with("left_s1"))
        .unwrap_or_else(|| panic!("no s1 row in\n{printed}"));
    assert!(s1.contains("linear"), "{s1}");
    assert_eq!(file["format_version"], 3);
    let terms = &file["payload"]["joint_terms"][1];
    assert_eq!(
        terms["spring_range"], file["payload"]["summary"]["training_range"][1],
        "{terms}"
    );
    // The same identification with the series continued everywhere.
    let series = tmp.path().join("series.ident.json");
    for t in file["payload"]["joint_terms"].as_array_mut().unwrap() {
        t["spring_range"] = Value::Null;
    }
    file["checksum"] = Value::String(checksum(&file["payload"]));
    std::fs::write(&series, serde_json::to_string(&file).unwrap()).unwrap();
    let urdf = root().join("models/baxter_left_arm.urdf");
    let rms = |ident: &std::path::Path| {
        let r = admittance(&[
            "evaluate",
            "--data",
            data.to_str().unwrap(),
            "--urdf",
            urdf.to_str().unwrap(),
            "--from",
            "120",
            "--identification",
            ident.to_str().unwrap(),
        ]);
        assert!(r.status.success(), "{}", text(&r));
        row(&text(&r), "identified + joint terms").0
    };
    let (along, bent) = (rms(&tangent), rms(&series));
    eprintln!("last 30 s, fitted on 0-60 s: tangent {along} N m, series {bent} N m");
    assert!(along < 0.5 * bent, "tangent {along} against series {bent}");
}
