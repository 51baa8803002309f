//! The angles of continuous joints kept on one branch. A driver may report a joint without
//! position limits wrapped to `(-pi, pi]` or `[0, 2 pi)` (Kinova Gen3's joints 1, 3, 5 and 7,
//! a PR2's wrist roll): the reading jumps by a whole turn while the joint moves a little.
//! Taken as it comes, that jump is a step the jump gate refuses for as long as the joint
//! would need to turn that far, and then a swing of thousands of rad/s for the filters, the
//! observer and the controller. The dynamics of such a joint repeat every turn, so the loop
//! moves each reading by whole turns to the branch nearest the joint's last accepted angle,
//! and a desired angle to the branch nearest the measured one (the controller then takes
//! the short way round).

use std::f64::consts::TAU;

use admittance_dynamics::{JointKind, Model};

/// The continuous joints of an arm and their last accepted angles; allocation-free per
/// sample.
#[derive(Clone, Debug)]
pub(crate) struct ContinuousAngles {
    /// Chain indices of the continuous joints.
    joints: Vec<usize>,
    /// Their last accepted angle (on the loop's branch), NaN before the first.
    last: Vec<f64>,
    /// Per chain joint, whether it is continuous.
    flags: Vec<bool>,
}

impl ContinuousAngles {
    /// The continuous joints of `model`.
    pub(crate) fn new(model: &Model) -> Self {
        let flags: Vec<bool> = model
            .joints
            .iter()
            .map(|j| j.kind == JointKind::Continuous)
            .collect();
        let joints: Vec<usize> = (0..flags.len()).filter(|&i| flags[i]).collect();
        let last = vec![f64::NAN; joints.len()];
        Self {
            joints,
            last,
            flags,
        }
    }

    /// Per chain joint, whether it is continuous (its angle counts on any turn).
    pub(crate) fn flags(&self) -> &[bool] {
        &self.flags
    }

    /// Moves each continuous joint's finite reading in `q` by whole turns to the branch
    /// nearest its last accepted angle (the first reading sets the branch).
    pub(crate) fn unwrap(&self, q: &mut [f64]) {
        self.nearest(q);
    }

    /// Takes the continuous joints' finite angles of `q` (after the gates: a refused value
    /// is NaN) as the branch for the next reading.
    pub(crate) fn accept(&mut self, q: &[f64]) {
        for (last, &i) in self.last.iter_mut().zip(&self.joints) {
            if let Some(&v) = q.get(i).filter(|v| v.is_finite()) {
                *last = v;
            }
        }
    }

    /// Moves each continuous joint's desired angle in `q_d` by whole turns to the branch
    /// nearest its last accepted measured angle.
    pub(crate) fn align(&self, q_d: &mut [f64]) {
        self.nearest(q_d);
    }

    fn nearest(&self, q: &mut [f64]) {
        for (&last, &i) in self.last.iter().zip(&self.joints) {
            let Some(v) = q.get_mut(i) else { continue };
            if v.is_finite() && last.is_finite() {
                let turns = ((last - *v) / TAU).round();
                // A finite reading far beyond any turn count is left to the gates.
                if turns != 0.0 && turns.abs() < 1e9 {
                    *v += turns * TAU;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const URDF: &str = r#"<robot name="r">
      <link name="base"/>
      <link name="a"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="b"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
        <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
      <joint name="j2" type="continuous"><parent link="a"/><child link="b"/><origin xyz="0.1 0 0"/>
        <axis xyz="0 0 1"/><limit effort="10" velocity="2"/></joint>
    </robot>"#;

    #[test]
    fn a_wrapped_reading_returns_to_the_branch_and_a_revolute_joint_is_left_alone() {
        let model = Model::from_urdf_str(URDF, "test", Some("base"), Some("b")).unwrap();
        let mut angles = ContinuousAngles::new(&model);
        let mut q = [3.1, 3.1];
        angles.unwrap(&mut q);
        assert_eq!(q, [3.1, 3.1]);
        angles.accept(&q);
        // The continuous joint crosses pi, reported wrapped; the revolute one is not touched.
        let mut q = [-3.1, 3.15 - TAU];
        angles.unwrap(&mut q);
        assert_eq!(q[0], -3.1);
        assert!((q[1] - 3.15).abs() < 1e-12, "{}", q[1]);
        angles.accept(&q);
        // A desired angle on another branch is brought next to the measured one.
        let mut q_d = [0.0, -3.0];
        angles.align(&mut q_d);
        assert!((q_d[1] - (TAU - 3.0)).abs() < 1e-12, "{}", q_d[1]);
        // A refused (NaN) reading keeps the branch; short slices are ignored.
        angles.accept(&[f64::NAN, f64::NAN]);
        let mut q = [0.0, 3.2 - 2.0 * TAU];
        angles.unwrap(&mut q);
        assert!((q[1] - 3.2).abs() < 1e-12, "{}", q[1]);
        angles.unwrap(&mut [0.0]);
    }
}
