//! An identification file is checked on load as its physics requires, not only against its
//! checksum: an edited file with its checksum recomputed is refused, naming the body or
//! joint and the value (issue 34, item 8).

use crate::common;
use admittance_dynamics::*;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// The file format's checksum (docs/outputs.md): FNV-1a 64 of the payload's JSON text.
fn checksum(payload: &Value) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in payload.to_string().bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Saves the URDF's own model as an identification, applies `edit` to its payload, puts
/// the recomputed checksum back and loads it.
fn load_edited(dir: &Path, edit: impl FnOnce(&mut Value)) -> Result<Identification, String> {
    let urdf = common::baxter();
    let path = dir.join("edited.ident.json");
    let _ = std::fs::remove_file(&path);
    Identification::from_model(urdf.clone())
        .save(&path, &urdf, BTreeMap::new())
        .unwrap();
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    // A bare model's summary has no measured errors (NaN, written as null): give it some.
    zero_nulls(&mut v["payload"]["summary"]);
    edit(&mut v["payload"]);
    v["checksum"] = Value::String(checksum(&v["payload"]));
    std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    Identification::load(&path, &urdf).map_err(|e| e.to_string())
}

fn zero_nulls(v: &mut Value) {
    match v {
        Value::Null => *v = 0.0.into(),
        Value::Array(a) => a.iter_mut().for_each(zero_nulls),
        Value::Object(o) => o.values_mut().for_each(zero_nulls),
        _ => {}
    }
}

#[test]
fn an_unedited_file_loads() {
    let dir = tempfile::tempdir().unwrap();
    load_edited(dir.path(), |_| {}).unwrap();
}

#[test]
fn a_negative_mass_is_refused_naming_the_body() {
    let dir = tempfile::tempdir().unwrap();
    let e = load_edited(dir.path(), |p| p["inertial_parameters"][20] = (-5.0).into()).unwrap_err();
    assert!(e.contains("body 2") && e.contains("mass -5 kg"), "{e}");
    assert!(e.contains("edited.ident.json"), "{e}");
}

#[test]
fn an_absurd_inertia_is_refused_with_its_value() {
    let dir = tempfile::tempdir().unwrap();
    let e = load_edited(dir.path(), |p| p["inertial_parameters"][14] = 1e300.into()).unwrap_err();
    assert!(
        e.contains("inertial_parameters[14]") && e.contains("body 1"),
        "{e}"
    );
    assert!(e.contains("1e300"), "{e}");
}

#[test]
fn an_impossible_inertia_is_refused_naming_the_body() {
    let dir = tempfile::tempdir().unwrap();
    // Ixx far beyond Iyy + Izz: no mass distribution has it (triangle inequality).
    let e = load_edited(dir.path(), |p| p["inertial_parameters"][4] = 50.0.into()).unwrap_err();
    assert!(
        e.contains("body 0") && e.contains("not physically possible"),
        "{e}"
    );
}

#[test]
fn negative_joint_terms_are_refused_naming_the_joint() {
    let dir = tempfile::tempdir().unwrap();
    let e = load_edited(dir.path(), |p| {
        p["joint_terms"][3]["armature"] = (-1.5).into()
    })
    .unwrap_err();
    assert!(
        e.contains("joint_terms[3]") && e.contains("rotor inertia -1.5"),
        "{e}"
    );
    let e = load_edited(dir.path(), |p| {
        p["joint_terms"][1]["viscous"] = (-4.84).into()
    })
    .unwrap_err();
    assert!(
        e.contains("joint_terms[1]") && e.contains("viscous friction -4.84"),
        "{e}"
    );
    let e = load_edited(dir.path(), |p| p["joint_terms"][0]["offset"] = 1e12.into()).unwrap_err();
    assert!(
        e.contains("joint_terms[0]") && e.contains("1e12") && e.contains("beyond"),
        "{e}"
    );
}

#[test]
fn renamed_joints_are_refused_naming_both_lists() {
    let dir = tempfile::tempdir().unwrap();
    let e = load_edited(dir.path(), |p| p["joints"][0] = "elsewhere".into()).unwrap_err();
    assert!(
        e.contains("[elsewhere,") && e.contains("the arm's chain has [left_s0,"),
        "{e}"
    );
}

#[test]
fn what_consumers_take_from_the_summary_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    for (hz, shown) in [(-5.0, "-5"), (1e300, "1e300")] {
        let e =
            load_edited(dir.path(), |p| p["summary"]["input_filter_hz"] = hz.into()).unwrap_err();
        assert!(
            e.contains("summary.input_filter_hz") && e.contains(shown),
            "{e}"
        );
    }
    let e = load_edited(dir.path(), |p| {
        p["summary"]["acceleration_gain"] = 3.0.into()
    })
    .unwrap_err();
    assert!(e.contains("summary.acceleration_gain is 3"), "{e}");
    let e = load_edited(dir.path(), |p| {
        p["summary"]["acceleration_power"] = serde_json::json!([1.0, -2.0, 0, 0, 0, 0, 0])
    })
    .unwrap_err();
    assert!(e.contains("summary.acceleration_power[1] is -2"), "{e}");
    let e = load_edited(dir.path(), |p| {
        p["summary"]["acceleration_power"] = serde_json::json!([1.0])
    })
    .unwrap_err();
    assert!(
        e.contains("summary.acceleration_power has 1 values for 7 joints"),
        "{e}"
    );
    let e = load_edited(dir.path(), |p| p["summary"]["prior_scale"] = (-1.0).into()).unwrap_err();
    assert!(e.contains("summary.prior_scale is -1"), "{e}");
    let e = load_edited(dir.path(), |p| {
        p["summary"]["delay_s"] = serde_json::json!([1e9, 0, 0, 0, 0, 0, 0])
    })
    .unwrap_err();
    assert!(e.contains("summary.delay_s holds 1e9 s"), "{e}");
    let e = load_edited(dir.path(), |p| {
        p["summary"]["training_range"] = serde_json::json!([[0.0, 1.0]])
    })
    .unwrap_err();
    assert!(
        e.contains("summary.training_range has 1 pairs for 7 joints"),
        "{e}"
    );
    let e = load_edited(dir.path(), |p| {
        p["summary"]["training_range"] = serde_json::json!(vec![[1.0, -1.0]; 7])
    })
    .unwrap_err();
    assert!(e.contains("summary.training_range holds [1, -1]"), "{e}");
    let e = load_edited(dir.path(), |p| {
        p["summary"]["training_speed"] = serde_json::json!([0.5, 0.5])
    })
    .unwrap_err();
    assert!(
        e.contains("summary.training_speed has 2 values for 7 joints"),
        "{e}"
    );
    let e = load_edited(dir.path(), |p| {
        p["summary"]["training_speed"] = serde_json::json!([0.5, 0.5, -0.5, 0.5, 0.5, 0.5, 0.5])
    })
    .unwrap_err();
    assert!(e.contains("summary.training_speed holds -0.5"), "{e}");
    let e = load_edited(dir.path(), |p| {
        p["summary"]["expected_false_torque_rms"] = serde_json::json!([0.1, -1.0])
    })
    .unwrap_err();
    assert!(
        e.contains("summary.expected_false_torque_rms holds -1"),
        "{e}"
    );
}

#[test]
fn a_spring_range_round_trips_as_version_3_and_a_reversed_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = common::baxter();
    let path = dir.path().join("sprung.ident.json");
    let mut ident = Identification::from_model(urdf.clone());
    ident.joint_terms[1].spring = [20.0, -4.0, 0.0, 0.0];
    ident.joint_terms[1].spring_range = Some([-0.7, 1.1]);
    ident.save(&path, &urdf, BTreeMap::new()).unwrap();
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    // Builds that predate the range would evaluate these springs otherwise: version 3.
    assert_eq!(v["format_version"], 3);
    let back = Identification::load(&path, &urdf).unwrap();
    assert_eq!(back.joint_terms[1].spring_range, Some([-0.7, 1.1]));
    assert_eq!(
        back.joint_terms[1].spring_torque(2.0),
        ident.joint_terms[1].spring_torque(2.0)
    );
    // Without a range the file stays version 2, which older builds read.
    let plain = dir.path().join("plain.ident.json");
    Identification::from_model(urdf.clone())
        .save(&plain, &urdf, BTreeMap::new())
        .unwrap();
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&plain).unwrap()).unwrap();
    assert_eq!(v["format_version"], 2);
    let e = load_edited(dir.path(), |p| {
        p["joint_terms"][2]["spring_range"] = serde_json::json!([1.0, -1.0])
    })
    .unwrap_err();
    assert!(
        e.contains("joint_terms[2]") && e.contains("spring range"),
        "{e}"
    );
}
