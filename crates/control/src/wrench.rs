//! The hand wrench from the joint estimate (docs/method.md section 2, task-space variant:
//! `tau_ext = J^T f`): the damped least-squares solution
//! `f = (J J^T + d^2 I)^-1 J tau_ext_hat` (exact when `J` has full row rank and `d = 0`),
//! with `J` the tip's geometric Jacobian at the measured angles, in the base axes and in the
//! tip's. Allocation-free after construction.

use admittance_dynamics::{frame_jacobian, Data, Model};
use nalgebra::{Matrix6, Vector6};

use crate::error::ConfigError;

/// The damping a wrench estimator uses when given 0 (m, the unit of the Jacobian's
/// translational singular values).
pub const DEFAULT_WRENCH_DAMPING: f64 = 1e-3;

/// The estimated wrench the environment applies at the tip: force x, y, z (N) then moment
/// x, y, z (N m) about the tip's origin.
pub struct WrenchEstimator {
    data: Data,
    damping: f64,
    base: Vector6<f64>,
    tip: Vector6<f64>,
}

impl WrenchEstimator {
    /// An estimator for `model` with damping `damping` (0 picks
    /// [`DEFAULT_WRENCH_DAMPING`]); an error at `wrench_damping` when it is negative or not
    /// finite.
    pub fn new(model: &Model, damping: f64) -> Result<Self, ConfigError> {
        let damping = if damping == 0.0 {
            DEFAULT_WRENCH_DAMPING
        } else {
            damping
        };
        if !(damping.is_finite() && damping > 0.0) {
            return Err(ConfigError::new(
                "wrench_damping",
                format!(
                    "must be finite and >= 0 (0 picks {DEFAULT_WRENCH_DAMPING}), got {damping}"
                ),
            ));
        }
        Ok(Self {
            data: Data::new(model),
            damping,
            base: Vector6::zeros(),
            tip: Vector6::zeros(),
        })
    }

    /// Updates the wrench at the angles `q` from the joint estimate `tau_ext`. Keeps the
    /// last value when `q` or the estimate is not finite or `J J^T` is singular.
    pub fn update(&mut self, model: &Model, q: &[f64], tau_ext: &[f64]) {
        self.update_at(model, q, tau_ext, model.tip_frame, tau_ext.len());
    }

    /// The wrench at the origin of frame `frame` (e.g. a touched link's, issue 31) from
    /// the estimate of the first `joints` joints only (a force on a link loads the joints
    /// before it only); with fewer than six such joints the damped solution is the
    /// smallest wrench that explains them (what the Jacobian allows). [`Self::tip`] then
    /// holds it in the frame's axes. Keeps the last value as [`Self::update`] does, and
    /// for a frame the model does not have.
    pub fn update_at(
        &mut self,
        model: &Model,
        q: &[f64],
        tau_ext: &[f64],
        frame: usize,
        joints: usize,
    ) {
        if !q.iter().chain(tau_ext).all(|x| x.is_finite()) {
            return;
        }
        let Ok(j) = frame_jacobian(model, &mut self.data, q, frame) else {
            return;
        };
        let mut a = Matrix6::<f64>::identity() * (self.damping * self.damping);
        let mut b = Vector6::<f64>::zeros();
        for (k, &t) in tau_ext.iter().enumerate().take(j.ncols().min(joints)) {
            let col = j.column(k);
            for r in 0..6 {
                b[r] += col[r] * t;
                for c in 0..6 {
                    a[(r, c)] += col[r] * col[c];
                }
            }
        }
        if let Some(chol) = a.cholesky() {
            self.base = chol.solve(&b);
            // The Jacobian refreshed the frame's placement: its rotation maps frame axes to
            // base axes.
            let r = self.data.frame_placements[frame].rotation;
            let force = r.transpose() * self.base.fixed_rows::<3>(0);
            let moment = r.transpose() * self.base.fixed_rows::<3>(3);
            self.tip.fixed_rows_mut::<3>(0).copy_from(&force);
            self.tip.fixed_rows_mut::<3>(3).copy_from(&moment);
        }
    }

    /// Back to zero (no contact).
    pub fn clear(&mut self) {
        self.base.fill(0.0);
        self.tip.fill(0.0);
    }

    /// The last wrench in the base link's axes.
    pub fn base(&self) -> &[f64] {
        self.base.as_slice()
    }

    /// The last wrench in the tip link's axes (what a force-torque sensor at the tip reads).
    pub fn tip(&self) -> &[f64] {
        self.tip.as_slice()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use admittance_dynamics::tip_jacobian;

    /// A torque that a hand wrench produces, `tau = J^T f`, gives that wrench back, in base
    /// axes and (rotated) in the tip's.
    #[test]
    fn wrench_inverts_the_jacobian_transpose() {
        let urdf = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/baxter_left_arm.urdf"
        );
        let model = Model::from_urdf_file(urdf.as_ref(), Some("base"), Some("left_hand")).unwrap();
        let q = [0.1, -0.9, 1.1, 1.8, -0.6, 1.0, -0.4];
        let f = Vector6::new(3.0, -2.0, 5.0, 0.4, -0.3, 0.2);
        let mut data = Data::new(&model);
        let j = tip_jacobian(&model, &mut data, &q).unwrap().clone();
        let tau: Vec<f64> = (0..7).map(|k| j.column(k).dot(&f)).collect();
        let mut w = WrenchEstimator::new(&model, 1e-6).unwrap();
        w.update(&model, &q, &tau);
        assert!((w.base - f).norm() < 1e-6, "{} vs {f}", w.base);
        let r = data.frame_placements[model.tip_frame].rotation;
        let force = r.transpose() * f.fixed_rows::<3>(0);
        let moment = r.transpose() * f.fixed_rows::<3>(3);
        assert!((w.tip.fixed_rows::<3>(0) - force).norm() < 1e-6);
        assert!((w.tip.fixed_rows::<3>(3) - moment).norm() < 1e-6);
        // A non-finite estimate keeps the last value.
        w.update(&model, &q, &[f64::NAN; 7]);
        assert!((w.base - f).norm() < 1e-6);
        assert!(WrenchEstimator::new(&model, -1.0).is_err());
    }

    /// A force on a link loads only the joints before it: from those joints' estimate the
    /// wrench at the link comes back when six of them load it, whatever the later joints
    /// read.
    #[test]
    fn the_wrench_at_a_touched_link_comes_from_the_joints_before_it() {
        let urdf = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/baxter_left_arm.urdf"
        );
        let model = Model::from_urdf_file(urdf.as_ref(), Some("base"), Some("left_hand")).unwrap();
        let q = [0.1, -0.9, 1.1, 1.8, -0.6, 1.0, -0.4];
        // The frame of joint 5's child link (w1's): six joints load it.
        let frame = model
            .frames
            .iter()
            .position(|f| f.parent_joint == Some(5))
            .unwrap();
        let f = Vector6::new(3.0, -2.0, 5.0, 0.4, -0.3, 0.2);
        let mut data = Data::new(&model);
        let j = frame_jacobian(&model, &mut data, &q, frame)
            .unwrap()
            .clone();
        let mut tau: Vec<f64> = (0..7).map(|k| j.column(k).dot(&f)).collect();
        assert!(tau[6].abs() < 1e-12, "joint 6 comes after the link");
        tau[6] = 9.0; // what the estimate reads beyond the link is not the link's wrench
        let mut w = WrenchEstimator::new(&model, 1e-6).unwrap();
        w.update_at(&model, &q, &tau, frame, 6);
        assert!((w.base - f).norm() < 1e-5, "{} vs {f}", w.base);
        let r = data.frame_placements[frame].rotation;
        assert!((w.tip.fixed_rows::<3>(0) - r.transpose() * f.fixed_rows::<3>(0)).norm() < 1e-5);
        w.clear();
        assert_eq!(w.base(), &[0.0; 6]);
    }
}
