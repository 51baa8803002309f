//! A stable fingerprint of an arm's model, so that files made for one arm (a trained
//! network, docs/outputs.md "Model files") can tell whether they are used with another.

use crate::model::Model;

/// Format tag hashed first: bump it when what the fingerprint covers changes.
const FINGERPRINT_TAG: &[u8] = b"admittance-arm-fingerprint-v1";

/// Significant decimal digits a number keeps before it is hashed.
const SIGNIFICANT_DIGITS: usize = 9;

/// Magnitudes below this count as zero (rounding residue such as `cos(pi / 2)`).
const ZERO_BELOW: f64 = 1e-12;

/// FNV-1a, 64 bit: small, fixed forever (unlike `std`'s hasher, whose output may change
/// between Rust releases), good enough to tell models apart (not a security hash).
struct Fnv1a(u64);

impl Fnv1a {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    /// A length-prefixed field, so that `("ab", "c")` and `("a", "bc")` differ.
    fn field(&mut self, bytes: &[u8]) {
        self.bytes(&(bytes.len() as u64).to_le_bytes());
        self.bytes(bytes);
    }

    fn number(&mut self, v: f64) {
        self.field(canonical_number(v).as_bytes());
    }

    fn numbers(&mut self, values: impl IntoIterator<Item = f64>) {
        for v in values {
            self.number(v);
        }
    }
}

/// The text a number is hashed as: 9 significant digits in scientific notation
/// (`1.00000000e0`), `0` for magnitudes below 1e-12 (and for -0), `inf` / `-inf`, `nan`.
fn canonical_number(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else if v.abs() < ZERO_BELOW {
        "0".into()
    } else {
        format!("{v:.prec$e}", prec = SIGNIFICANT_DIGITS - 1)
    }
}

impl Model {
    /// A 64-bit fingerprint of what determines the arm's joint torques: two models with the
    /// same fingerprint have the same joints and bodies (up to 9 significant digits).
    ///
    /// It covers, in chain order, for every moving joint: its name, kind (revolute,
    /// continuous, prismatic), axis, placement (rotation matrix and translation of the
    /// joint frame in the previous body's frame, fixed joints folded in), limits (lower,
    /// upper, velocity, effort; absent ones as infinite) and `<dynamics>` damping and
    /// friction; and for every moving body (fixed children and locked branches folded in)
    /// its mass, first mass moment `m c` (c: centre of mass) and rotational inertia about
    /// the joint frame, which together fix the mass, centre of mass and inertia.
    ///
    /// It does not cover the robot's name, the file it came from, the base and tip link
    /// names, the frames beyond the joints (they move no mass), the gravity vector (a
    /// setting of the model, not of the arm) or excluded branches.
    ///
    /// Independent of how the numbers were written: every number is rounded to 9
    /// significant digits before hashing and magnitudes below 1e-12 count as 0, so `1`,
    /// `1.0`, `1e0` and `0.99999999999999` give the same fingerprint, and so do rotation
    /// entries that differ only by rounding residue (`6e-17` against `0`). Hash:
    /// FNV-1a 64 over a tagged, length-prefixed encoding (stable across builds and
    /// platforms; not a cryptographic hash).
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv1a::new();
        h.field(FINGERPRINT_TAG);
        h.bytes(&(self.joints.len() as u64).to_le_bytes());
        for joint in &self.joints {
            h.field(joint.name.as_bytes());
            h.field(joint.kind.as_str().as_bytes());
            h.numbers(joint.axis.iter().copied());
            h.numbers(joint.placement.rotation.iter().copied());
            h.numbers(joint.placement.translation.iter().copied());
            let l = &joint.limits;
            h.numbers([l.lower, l.upper, l.velocity, l.effort]);
            h.numbers([joint.damping, joint.friction]);
        }
        h.bytes(&(self.bodies.len() as u64).to_le_bytes());
        for body in &self.bodies {
            h.number(body.mass);
            h.numbers(body.first_moment.iter().copied());
            h.numbers(body.rotational.iter().copied());
        }
        h.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const URDF: &str = r#"<robot name="two">
      <link name="base"/>
      <link name="a"><inertial><origin xyz="0 0 0.1"/><mass value="2"/>
        <inertia ixx="0.01" iyy="0.01" izz="0.005" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="b"><inertial><origin xyz="0.05 0 0"/><mass value="1.5"/>
        <inertia ixx="0.004" iyy="0.004" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
        <origin xyz="0 0 0.2" rpy="0 0 0"/><axis xyz="0 0 1"/>
        <limit lower="-2" upper="2" velocity="3" effort="50"/></joint>
      <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
        <origin xyz="0 0 0.3" rpy="1.5707963267948966 0 0"/><axis xyz="0 1 0"/>
        <limit lower="-1.5" upper="1.5" velocity="3" effort="30"/></joint>
    </robot>"#;

    fn model(text: &str) -> Model {
        Model::from_urdf_str(text, "test.urdf", None, None).unwrap()
    }

    #[test]
    fn same_arm_same_fingerprint_whatever_the_number_formatting() {
        let a = model(URDF);
        // The same numbers written differently, and a different robot name.
        let reformatted = URDF
            .replace("name=\"two\"", "name=\"other_name\"")
            .replace("value=\"2\"", "value=\"2.000\"")
            .replace("ixx=\"0.01\"", "ixx=\"1e-2\"")
            .replace("xyz=\"0 0 0.3\"", "xyz=\"0.0 0.0 3.0e-1\"")
            .replace("1.5707963267948966", "1.57079632679489661923");
        let b = model(&reformatted);
        assert_eq!(a.fingerprint(), b.fingerprint());
        // Stable across calls and clones.
        assert_eq!(a.fingerprint(), a.clone().fingerprint());
        // The gravity setting is not part of the arm.
        let mut g = a.clone();
        g.gravity.z = -1.62;
        assert_eq!(a.fingerprint(), g.fingerprint());
    }

    #[test]
    fn every_covered_quantity_changes_the_fingerprint() {
        let base = model(URDF).fingerprint();
        let changes = [
            ("name=\"j2\"", "name=\"j2b\""),
            (
                "type=\"revolute\"><parent link=\"a\"",
                "type=\"prismatic\"><parent link=\"a\"",
            ),
            ("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"1 0 0\"/>"),
            ("xyz=\"0 0 0.3\"", "xyz=\"0 0 0.31\""),
            ("rpy=\"1.5707963267948966 0 0\"", "rpy=\"1.5 0 0\""),
            ("lower=\"-1.5\"", "lower=\"-1.4\""),
            ("effort=\"30\"", "effort=\"31\""),
            ("value=\"1.5\"", "value=\"1.6\""),
            ("<origin xyz=\"0.05 0 0\"/>", "<origin xyz=\"0.06 0 0\"/>"),
            ("izz=\"0.002\"", "izz=\"0.0021\""),
        ];
        for (from, to) in changes {
            assert!(URDF.contains(from), "{from}");
            let changed = model(&URDF.replacen(from, to, 1)).fingerprint();
            assert_ne!(changed, base, "{from} -> {to} kept the fingerprint");
        }
        // Scaled inertias (a nominal model 20 % off) are another arm.
        let m = model(URDF);
        assert_ne!(m.with_scaled_inertias(1.2).unwrap().fingerprint(), base);
    }

    #[test]
    fn numbers_are_canonical() {
        assert_eq!(canonical_number(1.0), canonical_number(1.000_000_000_000_1));
        assert_eq!(canonical_number(0.0), canonical_number(-0.0));
        assert_eq!(canonical_number(6.123e-17), "0");
        assert_eq!(canonical_number(f64::INFINITY), "inf");
        assert_ne!(canonical_number(1.0), canonical_number(1.000_001));
        assert_eq!(canonical_number(1.0), "1.00000000e0");
    }
}
