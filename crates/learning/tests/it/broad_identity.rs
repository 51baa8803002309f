//! Model files that know what they are: the arm (joint names, fingerprint) and every
//! setting that made them survive a save and load; users check them; version-1 files
//! (which know none of it) still load, as "unrecorded".

use crate::broad_common;
use admittance_learning::broad::{
    fit, fnv1a64, ArmCheck, ArmIdentity, BroadError, BroadModel, DataSettings, Dataset, GrowthSpec,
    TrainingTarget, ValidationSplit,
};
use broad_common::{data, small_config};

fn fitted() -> (BroadModel, Vec<f64>, Vec<f64>) {
    let (x, y) = data(600, 5, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(20);
    cfg.lambda_grid = vec![1e-6];
    (fit(&train, None, &cfg).unwrap().0, x, y)
}

fn arm() -> ArmIdentity {
    ArmIdentity::new(["shoulder", "elbow"], 0x1234_5678_9abc_def0)
}

fn settings() -> DataSettings {
    DataSettings {
        input_filter_hz: 10.0,
        validation: ValidationSplit::TrailingFraction { fraction: 0.2 },
        target: TrainingTarget::NominalResidual {
            nominal_inertia_scale: 1.2,
        },
    }
}

#[test]
fn identity_and_settings_survive_save_and_load() {
    let (mut m, x, y) = fitted();
    m.set_arm(arm()).unwrap();
    m.set_data_settings(settings()).unwrap();
    let fit_settings = m.provenance().fit.clone().unwrap();
    assert_eq!(fit_settings.nodes, 20);
    assert_eq!(fit_settings.lambda_grid, vec![1e-6]);
    assert_eq!(fit_settings.centres.as_ref().unwrap().seed, 11);
    // Growth is recorded too.
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    m.grow(
        &train,
        &GrowthSpec::KMeansPlusPlus { count: 4, seed: 9 },
        &small_config(20),
    )
    .unwrap();
    assert_eq!(m.provenance().growth.len(), 1);
    assert_eq!(m.provenance().growth[0].nodes_added, 4);
    let back = BroadModel::from_bytes(&m.to_bytes(), "mem").unwrap();
    assert_eq!(back.provenance(), m.provenance());
    assert_eq!(back.arm(), Some(&arm()));
    assert_eq!(back.check_arm(&arm()).unwrap(), ArmCheck::Matches);
    assert_eq!(
        back.check_data_settings(&settings()).unwrap(),
        ArmCheck::Matches
    );
    // A stripped deployment copy keeps its identity.
    let mut stripped = back.clone();
    stripped.strip_growth_state();
    let stripped = BroadModel::from_bytes(&stripped.to_bytes(), "mem").unwrap();
    assert_eq!(stripped.provenance(), m.provenance());
    // The arm must fit the outputs.
    let mut other = fitted().0;
    assert!(matches!(
        other.set_arm(ArmIdentity::new(["a", "b", "c"], 1)),
        Err(BroadError::Config(_))
    ));
    assert!(other
        .set_data_settings(DataSettings {
            input_filter_hz: f64::NAN,
            ..settings()
        })
        .is_err());
}

#[test]
fn another_arm_is_refused_saying_what_differs() {
    let (mut m, _, _) = fitted();
    m.set_arm(arm()).unwrap();
    let renamed = ArmIdentity::new(["shoulder", "wrist"], arm().fingerprint);
    match m.check_arm(&renamed) {
        Err(e @ BroadError::ArmMismatch(_)) => {
            let msg = e.to_string();
            assert!(msg.contains("[shoulder, elbow]"), "{msg}");
            assert!(msg.contains("joint 2 is `wrist`, not `elbow`"), "{msg}");
        }
        other => panic!("{other:?}"),
    }
    let reweighed = ArmIdentity::new(["shoulder", "elbow"], 42);
    match m.check_arm(&reweighed) {
        Err(e @ BroadError::ArmMismatch(_)) => {
            let msg = e.to_string();
            assert!(msg.contains("123456789abcdef0"), "{msg}");
            assert!(msg.contains("000000000000002a"), "{msg}");
            assert!(msg.contains("mass"), "{msg}");
        }
        other => panic!("{other:?}"),
    }
    // Joint names alone (data that carry no arm model).
    assert_eq!(
        m.check_joints(&["shoulder", "elbow"]).unwrap(),
        ArmCheck::Matches
    );
    assert!(matches!(
        m.check_joints(&["elbow", "shoulder"]),
        Err(BroadError::ArmMismatch(_))
    ));
    // Other data settings.
    m.set_data_settings(settings()).unwrap();
    let unfiltered = DataSettings {
        input_filter_hz: 0.0,
        target: TrainingTarget::FreeMotionTorque,
        ..settings()
    };
    match m.check_data_settings(&unfiltered) {
        Err(e @ BroadError::SettingsMismatch(_)) => {
            let msg = e.to_string();
            assert!(msg.contains("input filter 10 Hz, not 0 Hz"), "{msg}");
            assert!(msg.contains("nominal model"), "{msg}");
        }
        other => panic!("{other:?}"),
    }
    // A model that records nothing says so rather than passing as a match.
    let (bare, _, _) = fitted();
    assert_eq!(bare.check_arm(&arm()).unwrap(), ArmCheck::Unrecorded);
    assert_eq!(
        bare.check_joints(&["x", "y"]).unwrap(),
        ArmCheck::Unrecorded
    );
}

/// The bytes of `m` as format version 1 wrote them: no provenance in the header.
fn as_version_1(m: &BroadModel) -> Vec<u8> {
    let bytes = m.to_bytes();
    let h_len = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + h_len]).unwrap();
    let obj = header.as_object_mut().unwrap();
    for key in ["written_by", "arm", "data", "fit", "growth"] {
        obj.remove(key);
    }
    obj.insert("format_version".into(), 1.into());
    let new_header = serde_json::to_vec(&header).unwrap();
    let mut out = bytes[..8].to_vec();
    out.extend_from_slice(&(new_header.len() as u64).to_le_bytes());
    out.extend_from_slice(&new_header);
    out.extend_from_slice(&bytes[16 + h_len..bytes.len() - 8]);
    let h = fnv1a64(&out);
    out.extend_from_slice(&h.to_le_bytes());
    out
}

#[test]
fn version_1_files_load_with_their_identity_unrecorded() {
    let (mut m, x, _) = fitted();
    m.set_arm(arm()).unwrap();
    let v1 = as_version_1(&m);
    let old = BroadModel::from_bytes(&v1, "old.broad").unwrap();
    assert_eq!(old.weights(), m.weights());
    assert!(old.has_growth_state());
    assert_eq!(old.provenance(), &Default::default());
    assert_eq!(old.check_arm(&arm()).unwrap(), ArmCheck::Unrecorded);
    let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
    let (mut wa, mut wb) = (m.workspace(), old.workspace());
    for r in x.chunks(3).take(50) {
        m.predict_into(r, &mut a, &mut wa).unwrap();
        old.predict_into(r, &mut b, &mut wb).unwrap();
        assert_eq!(a, b);
    }
    // Saved again, it becomes a version-2 file.
    let again = old.to_bytes();
    assert!(String::from_utf8_lossy(&again[..200]).contains("\"format_version\":2"));
}

#[test]
fn a_corrupted_identity_is_a_format_error() {
    let (mut m, _, _) = fitted();
    m.set_arm(arm()).unwrap();
    let bytes = m.to_bytes();
    let h_len = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + h_len]).unwrap();
    header["arm"]["joints"] = serde_json::json!(["only_one"]);
    let new_header = serde_json::to_vec(&header).unwrap();
    let mut out = bytes[..8].to_vec();
    out.extend_from_slice(&(new_header.len() as u64).to_le_bytes());
    out.extend_from_slice(&new_header);
    out.extend_from_slice(&bytes[16 + h_len..bytes.len() - 8]);
    let h = fnv1a64(&out);
    out.extend_from_slice(&h.to_le_bytes());
    match BroadModel::from_bytes(&out, "bad.broad") {
        Err(e @ BroadError::Format { .. }) => {
            assert!(e.to_string().contains("1 arm joints for 2 outputs"), "{e}")
        }
        other => panic!("{other:?}"),
    }
}
