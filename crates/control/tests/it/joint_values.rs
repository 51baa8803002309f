//! `JointValues` (a number for every joint, or a list of one number per joint) says what is
//! accepted when a scenario gives something else (issue 14: the error used to be serde's
//! `data did not match any variant of untagged enum JointValues`).

use admittance_control::{AdmittanceConfig, JointValues};
use serde::Deserialize;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Holder {
    k: JointValues,
}

fn parse(text: &str) -> Result<JointValues, String> {
    toml::from_str::<Holder>(text)
        .map(|h| h.k)
        .map_err(|e| e.to_string())
}

const ACCEPTED: &str =
    "expected a number (one value for every joint) or a list of one number per joint";

#[test]
fn numbers_and_lists_of_numbers_are_accepted() {
    assert_eq!(parse("k = 12").unwrap(), JointValues::Uniform(12.0));
    assert_eq!(parse("k = -0.5").unwrap(), JointValues::Uniform(-0.5));
    assert_eq!(
        parse("k = inf").unwrap(),
        JointValues::Uniform(f64::INFINITY)
    );
    assert_eq!(
        parse("k = [1, 2.5, -3]").unwrap(),
        JointValues::PerJoint(vec![1.0, 2.5, -3.0])
    );
    assert_eq!(parse("k = []").unwrap(), JointValues::PerJoint(vec![]));
    // JSON too, and what is written reads back.
    for v in [
        JointValues::Uniform(3.0),
        JointValues::PerJoint(vec![1.0, 0.25]),
    ] {
        let json = serde_json::to_string(&v).unwrap();
        assert_eq!(serde_json::from_str::<JointValues>(&json).unwrap(), v);
    }
    assert_eq!(
        serde_json::to_string(&JointValues::Uniform(3.0)).unwrap(),
        "3.0"
    );
}

#[test]
fn a_value_of_the_wrong_shape_says_what_is_accepted() {
    for (text, found) in [
        (r#"k = "12""#, r#"found the string "12""#),
        ("k = true", "found the boolean true"),
        ("k = { a = 1 }", "found a table"),
        ("k = 1979-05-27", "found"),
    ] {
        let e = parse(text).unwrap_err();
        assert!(e.contains(ACCEPTED), "{text}: {e}");
        assert!(e.contains(found), "{text}: {e}");
        assert!(!e.contains("untagged"), "{text}: {e}");
        // toml adds the line and the key's value.
        assert!(e.contains("line 1"), "{text}: {e}");
    }
}

#[test]
fn a_list_element_of_the_wrong_shape_names_the_joint() {
    let e = parse(r#"k = [1.0, 2.0, "3"]"#).unwrap_err();
    assert!(
        e.contains(r#"joint 2: expected a number, found the string "3""#),
        "{e}"
    );
    let e = parse("k = [1.0, [2.0]]").unwrap_err();
    assert!(
        e.contains("joint 1: expected a number, found a list"),
        "{e}"
    );
    assert!(!e.contains("untagged"), "{e}");
    let e = serde_json::from_str::<JointValues>(r#"[1, null]"#).unwrap_err();
    assert!(
        e.to_string()
            .contains("joint 1: expected a number, found no value"),
        "{e}"
    );
    let e = serde_json::from_str::<JointValues>(r#""a""#).unwrap_err();
    assert!(e.to_string().contains(ACCEPTED), "{e}");
}

#[test]
fn the_message_reaches_a_configuration_that_holds_joint_values() {
    let e = toml::from_str::<AdmittanceConfig>("damping = \"3\"\nstiffness = 5\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains(ACCEPTED) && e.contains("damping"), "{e}");
    let ok = toml::from_str::<AdmittanceConfig>("damping = 3\nstiffness = [5, 5]\n").unwrap();
    assert_eq!(ok.damping, JointValues::Uniform(3.0));
    assert_eq!(ok.stiffness, JointValues::PerJoint(vec![5.0, 5.0]));
}
