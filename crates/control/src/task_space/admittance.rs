//! [`TaskSpaceAdmittance`]: the compliant hand pose and its joint reference.

use std::sync::Arc;

use admittance_dynamics::{tip_jacobian, Data, Model, Transform};
use nalgebra::{Matrix6xX, Vector3, Vector6};

use super::config::{TaskSaturationConfig, TaskSpaceAdmittanceConfig};
use super::damped_inverse::DampedPseudoInverse;
use super::deviation::AxisDeviation;
use super::hand::{
    hand_motion, jacobian_times, keep_task_entries, keep_task_rows, relative_rotation,
};
use super::so3;
use crate::admittance::{Saturation, SaturationConfig};
use crate::config::{Bound, JointValues};
use crate::error::{ConfigError, Fault, StepStatus};
use crate::reference::ReferenceInput;
use crate::safe_hold::first_non_finite;

/// The hand's motion of one step (steps 1-3 of [`TaskSpaceAdmittance`]), before commit.
struct HandReference {
    desired_pose: Transform,
    desired_twist: Vector6<f64>,
    wrench: Vector6<f64>,
    /// `dx`, `dx'`, `dx''` after the step.
    deviation: [Vector6<f64>; 3],
    compliant_pose: Transform,
    compliant_twist: Vector6<f64>,
    compliant_acceleration: Vector6<f64>,
}

/// Input of one [`TaskSpaceAdmittance`] step (the same as every
/// [`CompliantReference`](crate::CompliantReference)'s): the desired joint trajectory, the
/// measured joint position and the external-torque estimate.
pub type TaskSpaceInput<'a> = ReferenceInput<'a>;

/// The task-space admittance model (the paper's eq. 5 on the hand, docs/method.md section 2,
/// task-space variant; issue 16 part 1).
///
/// # Per step
///
/// 1. **Desired hand motion** from the desired joint trajectory by forward kinematics:
///    `x_d = FK(q_d)`, `x_d' = J(q_d) q_d'`, `x_d'' = J(q_d) q_d'' + J'(q_d, q_d') q_d'`
///    (hand = the model's tip frame; linear part first, base axes; twists are the tip
///    origin's velocity and the angular velocity).
/// 2. **Wrench estimate** `f_ext_hat = J(q)^#T tau_ext_hat` at the *measured* `q`, with
///    the damped pseudo-inverse described below (force in N at the tip origin and moment in
///    N m about it, base axes; `tau_ext = J^T f` is docs/method.md's task-space contact). Only
///    the rows of the task axes enter `J` (the wrench is estimated on them and is zero on
///    the others: a planar arm with task axes x and z reads the force in its plane).
/// 3. **Admittance** per compliant axis, `M_d dx'' + C_d dx' + G_d dx = f_ext_hat` with
///    `dx = x_r - x_d` (see `deviation.rs`: exact without `M_d`, backward Euler with it;
///    the wrench is held over the step). Positions: `p_r = p_d + dx_lin`. Orientations: the
///    deviation is a rotation vector `dtheta` in the base frame, `R_r = Exp(dtheta) R_d`,
///    and its rates are added to the desired angular velocity and acceleration
///    (`w_r = w_d + dtheta'`, exact to first order in `dtheta`; the inverse kinematics
///    below closes the loop on the exact SO(3) error, so `R_r` itself is tracked). A
///    non-compliant axis keeps `dx = 0`: it follows `x_d` rigidly.
/// 4. **Inverse kinematics** (second order, damped least squares) for the joint state
///    `q_a = q_d + dq`, `q_a' = q_d' + dq'`: with `J = J(q_a)` restricted to the task axes,
///    the pose error `e = [p_r - p(q_a); Log(R_r R(q_a)^T)]` and the twist error
///    `e' = x_r' - J q_a'` (both on the task axes),
///
///    ```text
///        a    = x_r'' - (J q_d'' + J' q_a') + K_D e' + K_P e          (task acceleration asked of dq'')
///        z    = -(K_ND dq' + K_NP dq)                                  (posture: towards q_d)
///        dq'' = J^# (a - J z) + z        (= J^# a + (I - J^# J) z, the null-space term)
///        dq'  <- dq' + dt dq'',   dq <- dq + dt dq'                    (semi-implicit Euler)
///    ```
///
///    so that `J q_a'' + J' q_a' = x_r'' + K_D e' + K_P e`: the hand follows `x_r` with the
///    error decaying as `e'' + K_D e' + K_P e = 0`. `J^#` is damped as in step 2 with the
///    IK's own [`SingularityDampingConfig`](crate::SingularityDampingConfig). When the arm
///    has more joints than task axes (Baxter's 7 on 6 axes, or fewer task axes) the
///    posture term pulls the self-motion towards `q_d`, and the hand is left to it on the
///    axes outside the task; with more task axes than joints the task is met in the
///    least-squares sense. Written on the deviation `dq` from `q_d`, every term is exactly
///    zero when there is no deviation: with a zero wrench estimate `q_a` is `q_d` bit for
///    bit (and `q_r` is the joint-space model's `q_r` for a zero estimate).
/// 5. **Saturation** (eq. 7, the joint-space [`Saturation`]): `q_r = sat(q_a)`,
///    `q_r' = sat'(q_a) q_a'`, `q_r'' = sat''(q_a) q_a'^2 + sat'(q_a) q_a''`; the state
///    `q_a` stays unsaturated.
///
/// As in the joint-space [`Admittance`](crate::Admittance), the state advanced over the step
/// is added to the desired values given with the step.
///
/// # Damped pseudo-inverse
///
/// Singular values `s_i` of `J` below `threshold` are damped by `lambda_i^2 = max_damping^2
/// (1 - (s_i / threshold)^2)`: zero damping away from singularities, the full `max_damping`
/// at a singular value of zero, and a gain `s_i / (s_i^2 + lambda_i^2)` that stays below
/// `threshold / min(max_damping, threshold)^2` (`1 / threshold` with the defaults) in every
/// direction. The damping used at the last step is [`wrench_damping`](Self::wrench_damping)
/// and [`ik_damping`](Self::ik_damping).
///
/// # Faults
///
/// Wrong lengths, a non-finite input, an invalid `dt`, or a result that is not finite
/// ([`Fault::NonFiniteOutput`]: e.g. an estimate so large that the wrench overflows; `joint`
/// is 0 when it is the hand's wrench or deviation) leave the state unchanged, keep the last `q_r` with zero velocity and acceleration (a
/// reference to hold; before the first good step `q_r = q_d` where finite) and return the
/// fault. `step` neither allocates nor panics.
#[derive(Clone, Debug)]
pub struct TaskSpaceAdmittance {
    model: Arc<Model>,
    data: Data,
    n: usize,
    /// The task axes (tracked by the inverse kinematics, estimated in the wrench).
    task: [bool; 6],
    deviation: AxisDeviation,
    position_gain: f64,
    velocity_gain: f64,
    posture_position_gain: f64,
    posture_velocity_gain: f64,
    wrench_inverse: DampedPseudoInverse,
    ik_inverse: DampedPseudoInverse,
    saturation: Option<Saturation>,
    /// `dq = q_a - q_d` and `dq'`.
    joint_deviation: Vec<f64>,
    joint_deviation_rate: Vec<f64>,
    q_a: Vec<f64>,
    qdot_a: Vec<f64>,
    qddot_a: Vec<f64>,
    q_r: Vec<f64>,
    qdot_r: Vec<f64>,
    qddot_r: Vec<f64>,
    wrench: Vector6<f64>,
    desired_pose: Transform,
    desired_twist: Vector6<f64>,
    compliant_pose: Transform,
    compliant_twist: Vector6<f64>,
    compliant_acceleration: Vector6<f64>,
    pose_error: Vector6<f64>,
    // Scratch.
    jacobian_desired: Matrix6xX<f64>,
    jacobian_measured: Matrix6xX<f64>,
    jacobian_reference: Matrix6xX<f64>,
    q_ik: Vec<f64>,
    qdot_ik: Vec<f64>,
    posture: Vec<f64>,
    joint_deviation_acceleration: Vec<f64>,
    /// Per-joint deadband on the estimate (issue 31, item 3); empty: none.
    deadband: Vec<f64>,
    /// The estimate through the deadband (scratch).
    deadbanded: Vec<f64>,
    has_output: bool,
}

impl TaskSpaceAdmittance {
    /// A task-space admittance for `model`'s hand (its tip frame). Errors name the key
    /// (`"linear.stiffness[2]"`, `"inverse_kinematics.damping.threshold"`,
    /// `"saturation.rho"`, ...).
    pub fn new(model: Arc<Model>, config: &TaskSpaceAdmittanceConfig) -> Result<Self, ConfigError> {
        let n = model.nq();
        if n == 0 {
            return Err(ConfigError::new("model", "has no moving joint"));
        }
        let (task, compliant) = axis_masks(config)?;
        let deviation = AxisDeviation::new(compliant, &config.linear, &config.angular)?;
        let ik = &config.inverse_kinematics;
        let gain = |key: &str, v: f64, bound: Bound| {
            bound
                .check(key, v)
                .map_err(|e| e.within("inverse_kinematics"))
        };
        let position_gain = gain("position_gain", ik.position_gain, Bound::Positive)?;
        let velocity_gain = gain("velocity_gain", ik.velocity_gain, Bound::Positive)?;
        let posture_position_gain = gain(
            "posture_position_gain",
            ik.posture_position_gain,
            Bound::NonNegative,
        )?;
        let posture_velocity_gain = gain(
            "posture_velocity_gain",
            ik.posture_velocity_gain,
            Bound::NonNegative,
        )?;
        let wrench_inverse = DampedPseudoInverse::new(n, task, &config.wrench_damping)
            .map_err(|e| e.within("wrench_damping"))?;
        let ik_inverse = DampedPseudoInverse::new(n, task, &ik.damping)
            .map_err(|e| e.within("inverse_kinematics.damping"))?;
        let saturation =
            build_saturation(&model, &config.saturation).map_err(|e| e.within("saturation"))?;
        let data = Data::new(&model);
        let zeros = vec![0.0; n];
        Ok(TaskSpaceAdmittance {
            model,
            data,
            n,
            task,
            deviation,
            position_gain,
            velocity_gain,
            posture_position_gain,
            posture_velocity_gain,
            wrench_inverse,
            ik_inverse,
            saturation,
            joint_deviation: zeros.clone(),
            joint_deviation_rate: zeros.clone(),
            q_a: zeros.clone(),
            qdot_a: zeros.clone(),
            qddot_a: zeros.clone(),
            q_r: zeros.clone(),
            qdot_r: zeros.clone(),
            qddot_r: zeros.clone(),
            wrench: Vector6::zeros(),
            desired_pose: Transform::identity(),
            desired_twist: Vector6::zeros(),
            compliant_pose: Transform::identity(),
            compliant_twist: Vector6::zeros(),
            compliant_acceleration: Vector6::zeros(),
            pose_error: Vector6::zeros(),
            jacobian_desired: Matrix6xX::zeros(n),
            jacobian_measured: Matrix6xX::zeros(n),
            jacobian_reference: Matrix6xX::zeros(n),
            q_ik: zeros.clone(),
            qdot_ik: zeros.clone(),
            posture: zeros.clone(),
            joint_deviation_acceleration: zeros.clone(),
            deadband: Vec::new(),
            deadbanded: zeros,
            has_output: false,
        })
    }

    /// The same admittance with a deadband on the joint-torque estimate per joint (N m),
    /// applied before the wrench is estimated: see [`crate::Admittance::with_deadband`].
    pub fn with_deadband(mut self, deadband: &[f64]) -> Result<Self, ConfigError> {
        self.set_deadband(deadband)?;
        Ok(self)
    }

    /// Sets the deadband in place (see `with_deadband`); on an error nothing changes.
    pub fn set_deadband(&mut self, deadband: &[f64]) -> Result<(), ConfigError> {
        self.deadband = crate::contact::checked_deadband(deadband, self.n)?;
        Ok(())
    }

    /// The deadband per joint (empty when there is none).
    pub fn deadband(&self) -> &[f64] {
        &self.deadband
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// The model whose hand (tip frame) is made compliant.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// The joint saturation of the reference, if any.
    pub fn saturation(&self) -> Option<&Saturation> {
        self.saturation.as_ref()
    }

    /// Back to the state just after construction (`x_r = x_d`, `q_a = q_d`).
    pub fn reset(&mut self) {
        self.deviation.reset();
        self.wrench_inverse.reset();
        self.ik_inverse.reset();
        for v in [
            &mut self.joint_deviation,
            &mut self.joint_deviation_rate,
            &mut self.q_a,
            &mut self.qdot_a,
            &mut self.qddot_a,
            &mut self.q_r,
            &mut self.qdot_r,
            &mut self.qddot_r,
        ] {
            v.fill(0.0);
        }
        self.wrench = Vector6::zeros();
        self.desired_pose = Transform::identity();
        self.desired_twist = Vector6::zeros();
        self.compliant_pose = Transform::identity();
        self.compliant_twist = Vector6::zeros();
        self.compliant_acceleration = Vector6::zeros();
        self.pose_error = Vector6::zeros();
        self.has_output = false;
    }

    /// Advances the model by `dt` (s) and computes the reference (see the type's
    /// documentation).
    pub fn step(&mut self, input: &TaskSpaceInput, dt: f64) -> StepStatus {
        match self.check(input, dt).and_then(|()| self.advance(input, dt)) {
            Ok(()) => {
                self.has_output = true;
                StepStatus::Ok
            }
            Err(fault) => {
                self.hold(input.q_d);
                StepStatus::Fault(fault)
            }
        }
    }

    /// The reference to hold after a fault.
    fn hold(&mut self, q_d: &[f64]) {
        self.qdot_r.fill(0.0);
        self.qddot_r.fill(0.0);
        if !self.has_output {
            for (r, d) in self.q_r.iter_mut().zip(q_d) {
                if d.is_finite() {
                    *r = *d;
                }
            }
        }
    }

    fn check(&self, input: &TaskSpaceInput, dt: f64) -> Result<(), Fault> {
        input.check(self.n)?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Fault::InvalidTimeStep);
        }
        if let Some(joint) = first_non_finite(input.q) {
            return Err(Fault::NonFiniteMeasurement {
                argument: "q",
                joint,
            });
        }
        Ok(())
    }

    /// One step on checked input; on an error nothing is committed.
    fn advance(&mut self, input: &TaskSpaceInput, dt: f64) -> Result<(), Fault> {
        let hand = self.hand_reference(input, dt)?;
        let pose_error = self.inverse_kinematics(input, &hand, dt)?;
        self.commit(input, &hand, pose_error);
        Ok(())
    }

    /// Steps 1-3: the desired hand motion, the wrench estimate and the compliant hand
    /// motion after the step (not committed).
    fn hand_reference(&mut self, input: &TaskSpaceInput, dt: f64) -> Result<HandReference, Fault> {
        let model = &*self.model;
        let (desired_pose, desired_twist, desired_acceleration) = hand_motion(
            model,
            &mut self.data,
            &mut self.jacobian_desired,
            input.q_d,
            input.qdot_d,
            input.qddot_d,
        )?;
        let j = tip_jacobian(model, &mut self.data, input.q)
            .map_err(|_| Fault::Internal("tip Jacobian"))?;
        self.jacobian_measured.copy_from(j);
        keep_task_rows(&mut self.jacobian_measured, &self.task);
        self.wrench_inverse.factor(&self.jacobian_measured)?;
        let estimate = if self.deadband.is_empty() {
            input.external_torque_estimate
        } else {
            for ((o, &e), &d) in self
                .deadbanded
                .iter_mut()
                .zip(input.external_torque_estimate)
                .zip(&self.deadband)
            {
                *o = crate::contact::soft_deadband(e, d);
            }
            &self.deadbanded
        };
        let mut wrench = self
            .wrench_inverse
            .transpose_apply(&self.jacobian_measured, estimate);
        keep_task_entries(&mut wrench, &self.task);
        let (mut dx, mut dx_rate, mut dx_acceleration) =
            (Vector6::zeros(), Vector6::zeros(), Vector6::zeros());
        self.deviation
            .advance(&wrench, dt, &mut dx, &mut dx_rate, &mut dx_acceleration);
        if !(wrench
            .iter()
            .chain(&dx)
            .chain(&dx_rate)
            .chain(&dx_acceleration))
        .all(|v| v.is_finite())
        {
            return Err(Fault::NonFiniteOutput { joint: 0 });
        }
        let dtheta: Vector3<f64> = dx.fixed_rows::<3>(3).into_owned();
        let compliant_pose = Transform {
            translation: desired_pose.translation + dx.fixed_rows::<3>(0),
            rotation: if dtheta == Vector3::zeros() {
                desired_pose.rotation
            } else {
                so3::exp(&dtheta) * desired_pose.rotation
            },
        };
        Ok(HandReference {
            desired_pose,
            desired_twist,
            wrench,
            deviation: [dx, dx_rate, dx_acceleration],
            compliant_pose,
            compliant_twist: desired_twist + dx_rate,
            compliant_acceleration: desired_acceleration + dx_acceleration,
        })
    }

    /// Step 4: `dq''` into `joint_deviation_acceleration`, the advanced `dq`, `dq'` into
    /// the scratch `q_ik`, `qdot_ik` (not committed); returns the pose error.
    fn inverse_kinematics(
        &mut self,
        input: &TaskSpaceInput,
        hand: &HandReference,
        dt: f64,
    ) -> Result<Vector6<f64>, Fault> {
        let n = self.n;
        for i in 0..n {
            self.q_ik[i] = input.q_d[i] + self.joint_deviation[i];
            self.qdot_ik[i] = input.qdot_d[i] + self.joint_deviation_rate[i];
        }
        let (pose, twist, feedforward) = hand_motion(
            &self.model,
            &mut self.data,
            &mut self.jacobian_reference,
            &self.q_ik,
            &self.qdot_ik,
            input.qddot_d,
        )?;
        let target = &hand.compliant_pose;
        let mut pose_error = Vector6::zeros();
        pose_error
            .fixed_rows_mut::<3>(0)
            .copy_from(&(target.translation - pose.translation));
        pose_error
            .fixed_rows_mut::<3>(3)
            .copy_from(&so3::log(&relative_rotation(
                &target.rotation,
                &pose.rotation,
            )));
        let mut task_acceleration = (hand.compliant_acceleration - feedforward)
            + (hand.compliant_twist - twist) * self.velocity_gain
            + pose_error * self.position_gain;
        keep_task_entries(&mut task_acceleration, &self.task);
        keep_task_rows(&mut self.jacobian_reference, &self.task);
        self.ik_inverse.factor(&self.jacobian_reference)?;
        for i in 0..n {
            self.posture[i] = -(self.posture_velocity_gain * self.joint_deviation_rate[i]
                + self.posture_position_gain * self.joint_deviation[i]);
        }
        let posture_task = jacobian_times(&self.jacobian_reference, &self.posture);
        self.ik_inverse.apply(
            &self.jacobian_reference,
            &(task_acceleration - posture_task),
            &mut self.joint_deviation_acceleration,
        );
        for (a, z) in self
            .joint_deviation_acceleration
            .iter_mut()
            .zip(&self.posture)
        {
            *a += z;
        }
        // Semi-implicit Euler into the scratch (q_ik, qdot_ik now hold dq, dq').
        for i in 0..n {
            self.qdot_ik[i] =
                self.joint_deviation_rate[i] + dt * self.joint_deviation_acceleration[i];
            self.q_ik[i] = self.joint_deviation[i] + dt * self.qdot_ik[i];
        }
        for v in [
            &self.q_ik,
            &self.qdot_ik,
            &self.joint_deviation_acceleration,
        ] {
            if let Some(joint) = first_non_finite(v) {
                return Err(Fault::NonFiniteOutput { joint });
            }
        }
        Ok(pose_error)
    }

    /// Step 5 and the commit of a successful step.
    fn commit(&mut self, input: &TaskSpaceInput, hand: &HandReference, pose_error: Vector6<f64>) {
        let [dx, dx_rate, dx_acceleration] = &hand.deviation;
        self.deviation.commit(dx, dx_rate, dx_acceleration);
        self.joint_deviation.copy_from_slice(&self.q_ik);
        self.joint_deviation_rate.copy_from_slice(&self.qdot_ik);
        self.wrench = hand.wrench;
        self.desired_pose = hand.desired_pose;
        self.desired_twist = hand.desired_twist;
        self.compliant_pose = hand.compliant_pose;
        self.compliant_twist = hand.compliant_twist;
        self.compliant_acceleration = hand.compliant_acceleration;
        self.pose_error = pose_error;
        for i in 0..self.n {
            self.q_a[i] = input.q_d[i] + self.joint_deviation[i];
            self.qdot_a[i] = input.qdot_d[i] + self.joint_deviation_rate[i];
            self.qddot_a[i] = input.qddot_d[i] + self.joint_deviation_acceleration[i];
            match &self.saturation {
                Some(sat) => {
                    let (r, ds, dds) = sat.apply(i, self.q_a[i]);
                    self.q_r[i] = r;
                    self.qdot_r[i] = ds * self.qdot_a[i];
                    self.qddot_r[i] = dds * self.qdot_a[i] * self.qdot_a[i] + ds * self.qddot_a[i];
                }
                None => {
                    self.q_r[i] = self.q_a[i];
                    self.qdot_r[i] = self.qdot_a[i];
                    self.qddot_r[i] = self.qddot_a[i];
                }
            }
        }
    }

    /// Reference position `q_r`.
    pub fn q_r(&self) -> &[f64] {
        &self.q_r
    }
    /// Reference velocity `q_r'`.
    pub fn qdot_r(&self) -> &[f64] {
        &self.qdot_r
    }
    /// Reference acceleration `q_r''`.
    pub fn qddot_r(&self) -> &[f64] {
        &self.qddot_r
    }
    /// Unsaturated joint state `q_a` of the inverse kinematics.
    pub fn q_a(&self) -> &[f64] {
        &self.q_a
    }
    /// `q_a'`.
    pub fn qdot_a(&self) -> &[f64] {
        &self.qdot_a
    }
    /// `q_a''`.
    pub fn qddot_a(&self) -> &[f64] {
        &self.qddot_a
    }
    /// The wrench estimate `f_ext_hat = J(q)^#T tau_ext_hat` of the last step: force (N) at
    /// the hand's origin, then moment (N m) about it, base axes.
    pub fn wrench_estimate(&self) -> &[f64] {
        self.wrench.as_slice()
    }
    /// The compliant hand pose `x_r` (position m, rotation; base frame).
    pub fn compliant_pose(&self) -> &Transform {
        &self.compliant_pose
    }
    /// Its twist `x_r'`: linear velocity (m/s) of the hand's origin, angular velocity
    /// (rad/s); base axes.
    pub fn compliant_twist(&self) -> &[f64] {
        self.compliant_twist.as_slice()
    }
    /// `x_r''` (m/s^2, rad/s^2).
    pub fn compliant_acceleration(&self) -> &[f64] {
        self.compliant_acceleration.as_slice()
    }
    /// The desired hand pose `x_d = FK(q_d)` of the last step.
    pub fn desired_pose(&self) -> &Transform {
        &self.desired_pose
    }
    /// Its twist `x_d' = J(q_d) q_d'`.
    pub fn desired_twist(&self) -> &[f64] {
        self.desired_twist.as_slice()
    }
    /// The deviation `dx = x_r - x_d` (m, then the rotation vector of `R_r R_d^T` in rad).
    pub fn deviation(&self) -> &[f64] {
        self.deviation.position.as_slice()
    }
    /// The inverse kinematics' pose error `x_r - FK(q_a)` at the last step, before its
    /// update (m, then rad).
    pub fn pose_error(&self) -> &[f64] {
        self.pose_error.as_slice()
    }
    /// The damping `lambda` of the wrench estimate's pseudo-inverse at the last step (0 away
    /// from singularities).
    pub fn wrench_damping(&self) -> f64 {
        self.wrench_inverse.damping()
    }
    /// The damping of the inverse kinematics' pseudo-inverse at the last step.
    pub fn ik_damping(&self) -> f64 {
        self.ik_inverse.damping()
    }
}

/// The task axes and the compliant axes of `config`, checked.
fn axis_masks(config: &TaskSpaceAdmittanceConfig) -> Result<([bool; 6], [bool; 6]), ConfigError> {
    if config.task_axes.is_empty() {
        return Err(ConfigError::new(
            "task_axes",
            "is empty: list the hand axes to track, e.g. [\"x\", \"y\", \"z\"]",
        ));
    }
    let mut task = [false; 6];
    for a in &config.task_axes {
        task[a.index()] = true;
    }
    let compliant = match &config.compliant_axes {
        None => task,
        Some(axes) => {
            let mut compliant = [false; 6];
            for a in axes {
                if !task[a.index()] {
                    return Err(ConfigError::new(
                        "compliant_axes",
                        format!(
                            "lists `{}`, which is not among `task_axes` (a compliant axis must be tracked)",
                            a.name()
                        ),
                    ));
                }
                compliant[a.index()] = true;
            }
            compliant
        }
    };
    Ok((task, compliant))
}

/// The joint saturation from its configuration.
fn build_saturation(
    model: &Model,
    config: &TaskSaturationConfig,
) -> Result<Option<Saturation>, ConfigError> {
    let n = model.nq();
    match config {
        TaskSaturationConfig::None => Ok(None),
        TaskSaturationConfig::Explicit(cfg) => Saturation::new(n, cfg).map(Some),
        TaskSaturationConfig::JointLimits { rho } => {
            let mut centre = Vec::with_capacity(n);
            let mut half_range = Vec::with_capacity(n);
            for (lo, hi) in model.position_limits() {
                if lo.is_finite() && hi.is_finite() && lo < hi {
                    centre.push(0.5 * (lo + hi));
                    half_range.push(0.5 * (hi - lo));
                } else {
                    centre.push(0.0);
                    half_range.push(f64::INFINITY);
                }
            }
            let cfg = SaturationConfig {
                rho: *rho,
                centre: JointValues::PerJoint(centre),
                half_range: JointValues::PerJoint(half_range),
            };
            Saturation::new(n, &cfg).map(Some)
        }
    }
}
