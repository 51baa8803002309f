//! Angles reported wrapped at +-pi (or 0-2 pi): put back on one branch before derivatives
//! are taken (`admittance_dynamics::unwrap_turns`), as `RobotLoop` does at run time; any
//! other step of more than pi stays refused (`check_jumps`).

use super::FreeMotionData;

impl FreeMotionData {
    /// Unwraps every joint whose angle reads as wrapped (`admittance_dynamics::unwrap_turns`:
    /// all its values within one turn, every step of more than pi a whole turn plus a step no
    /// joint moves that fast), to the branch of its first row, and adds its name to
    /// `unwrapped`. Before derivatives are taken.
    pub fn unwrap_turns(&mut self) {
        let n = self.dof();
        let t = &self.t;
        for i in 0..n {
            if admittance_dynamics::unwrap_turns(&mut self.q, n, i, |k| t[k] - t[k - 1]) {
                self.unwrapped.push(self.joints[i].clone());
            }
        }
    }

    /// What the loader did to wrapped angles, for the caller to say (`None`: nothing).
    pub fn unwrapped_note(&self) -> Option<String> {
        (!self.unwrapped.is_empty()).then(|| {
            let columns: Vec<String> = self.unwrapped.iter().map(|j| format!("q.{j}")).collect();
            format!(
                "{} read within one turn (a continuous joint's angle, wrapped): put back on one \
                 branch, as the run-time loop does",
                columns.join(", ")
            )
        })
    }
}
