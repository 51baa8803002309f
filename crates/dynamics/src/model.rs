//! The immutable description of a serial arm, built once (from a URDF) and shared by
//! every algorithm. Mutable per-call state lives in [`crate::Data`].

use nalgebra::{Matrix3, Vector3};

use crate::error::{DynamicsError, LoadWarning};
use crate::spatial::{axis_angle, Inertia, Motion, Transform};

/// The kinds of moving joint the chain supports. Fixed joints are folded away at load
/// time (their child's inertia joins the moving body, their frames stay addressable).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the axis, with position limits.
    Revolute,
    /// Rotation about the axis without position limits (the coordinate is the angle).
    Continuous,
    /// Translation along the axis.
    Prismatic,
}

impl JointKind {
    /// The URDF spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
        }
    }
}

/// Position, velocity and effort limits of a joint (URDF `<limit>`). Absent limits are
/// infinite (continuous joints have no position limits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointLimits {
    /// Lower position limit (rad or m).
    pub lower: f64,
    /// Upper position limit (rad or m).
    pub upper: f64,
    /// Velocity limit (rad/s or m/s).
    pub velocity: f64,
    /// Effort limit (N m or N).
    pub effort: f64,
}

impl Default for JointLimits {
    fn default() -> Self {
        Self {
            lower: f64::NEG_INFINITY,
            upper: f64::INFINITY,
            velocity: f64::INFINITY,
            effort: f64::INFINITY,
        }
    }
}

/// One moving joint of the chain and the rigid body it carries.
#[derive(Clone, Debug)]
pub struct Joint {
    /// The URDF joint name.
    pub name: String,
    /// Revolute, continuous or prismatic.
    pub kind: JointKind,
    /// Unit axis in the joint frame.
    pub axis: Vector3<f64>,
    /// Placement of the joint frame (at q = 0) in the previous moving body's frame (or the
    /// base frame for the first joint), fixed joints in between included.
    pub placement: Transform,
    /// Limits from `<limit>`.
    pub limits: JointLimits,
    /// Viscous damping from `<dynamics damping>` (N m s/rad or N s/m).
    pub damping: f64,
    /// Static friction from `<dynamics friction>` (N m or N).
    pub friction: f64,
    /// The URDF link that this joint moves.
    pub child_link: String,
}

impl Joint {
    /// The joint's motion subspace in its own frame (the unit twist of `qdot = 1`).
    #[inline(always)]
    pub fn motion_subspace(&self) -> Motion {
        match self.kind {
            JointKind::Prismatic => Motion {
                linear: self.axis,
                angular: Vector3::zeros(),
            },
            _ => Motion {
                linear: Vector3::zeros(),
                angular: self.axis,
            },
        }
    }

    /// `S^T f`: the component of a wrench (in this joint's frame) along the joint.
    #[inline(always)]
    pub fn subspace_dot(&self, f: &crate::spatial::Force) -> f64 {
        match self.kind {
            JointKind::Prismatic => self.axis.dot(&f.linear),
            _ => self.axis.dot(&f.angular),
        }
    }

    /// Placement of the joint frame at coordinate `q` in the parent body's frame.
    #[inline(always)]
    pub fn transform(&self, q: f64) -> Transform {
        match self.kind {
            JointKind::Prismatic => Transform {
                rotation: self.placement.rotation,
                translation: self.placement.translation + self.placement.rotation * (self.axis * q),
            },
            _ => Transform {
                rotation: rotate_about_axis(&self.placement.rotation, &self.axis, q),
                translation: self.placement.translation,
            },
        }
    }
}

/// `p * R(axis, q)`, with the common case of a coordinate axis (most URDFs) done on
/// columns instead of a full Rodrigues rotation and 3x3 product.
#[inline(always)]
fn rotate_about_axis(p: &Matrix3<f64>, axis: &Vector3<f64>, q: f64) -> Matrix3<f64> {
    let (s, c) = q.sin_cos();
    let (c0, c1, c2) = (p.column(0), p.column(1), p.column(2));
    if axis.x == 0.0 && axis.y == 0.0 {
        let s = s * axis.z;
        Matrix3::from_columns(&[c0 * c + c1 * s, c1 * c - c0 * s, c2.into_owned()])
    } else if axis.y == 0.0 && axis.z == 0.0 {
        let s = s * axis.x;
        Matrix3::from_columns(&[c0.into_owned(), c1 * c + c2 * s, c2 * c - c1 * s])
    } else if axis.x == 0.0 && axis.z == 0.0 {
        let s = s * axis.y;
        Matrix3::from_columns(&[c0 * c - c2 * s, c1.into_owned(), c2 * c + c0 * s])
    } else {
        p * axis_angle(axis, q)
    }
}

/// A named frame on the chain: a URDF link (the moving bodies' own links, links behind
/// fixed joints, and links of the base).
#[derive(Clone, Debug)]
pub struct Frame {
    /// The URDF link name.
    pub name: String,
    /// The moving joint whose body carries this frame; `None` for frames fixed to the base.
    pub parent_joint: Option<usize>,
    /// Placement in the carrying body's frame (or the base frame).
    pub placement: Transform,
}

/// Mass of one URDF link and the body it was folded into.
#[derive(Clone, Debug)]
pub struct LinkMass {
    /// The URDF link name.
    pub link: String,
    /// Its mass (kg); zero when the link has no `<inertial>`.
    pub mass: f64,
    /// The moving joint whose body carries it; `None` when it is part of the base.
    pub joint: Option<usize>,
}

/// A moving branch of the URDF off the chain (a gripper's fingers, a head, another arm)
/// that the model carries rigidly, its joints held at fixed positions: Pinocchio's
/// reduced model (`buildReducedModel` with those joints locked).
#[derive(Clone, Debug, PartialEq)]
pub struct LockedBranch {
    /// The joint where the branch leaves the chain (or the base): the first moving joint
    /// off it.
    pub joint: String,
    /// Every joint of the branch that can move, in file order within the branch's tree
    /// walk, with the position it is held at (rad or m; floating and planar joints are
    /// held at the identity and listed with 0).
    pub joints: Vec<(String, f64)>,
    /// Mass of the links of the branch (kg), dropped sub-branches excluded.
    pub mass: f64,
    /// The moving joint whose body carries the branch; `None` when it hangs off the fixed
    /// base (its mass then affects nothing).
    pub carried_by: Option<usize>,
}

/// A branch of the URDF left out of the model on request (its mass is not carried).
#[derive(Clone, Debug, PartialEq)]
pub struct DroppedBranch {
    /// The joint whose subtree was removed.
    pub joint: String,
    /// The links removed with it.
    pub links: Vec<String>,
    /// Their mass (kg), as far as the file states it readably (the dropped part is not
    /// validated).
    pub mass: f64,
}

/// A rigid payload attached at the tip frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Payload {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the tip frame (m).
    pub com: Vector3<f64>,
    /// Rotational inertia about the centre of mass, tip-frame axes (kg m^2).
    pub inertia: Matrix3<f64>,
}

impl Payload {
    /// A point mass at `com` in the tip frame.
    pub fn point_mass(mass: f64, com: Vector3<f64>) -> Self {
        Self {
            mass,
            com,
            inertia: Matrix3::zeros(),
        }
    }
}

/// A serial kinematic chain with its inertial parameters (the immutable half of the
/// Pinocchio-style `Model`/`Data` split).
#[derive(Clone, Debug)]
pub struct Model {
    /// The URDF `<robot name>`.
    pub robot_name: String,
    /// Where the model came from (file path or a source name).
    pub source: String,
    /// The base link: the frame every result is expressed in.
    pub base_link: String,
    /// Moving joints in chain order (index = coordinate index).
    pub joints: Vec<Joint>,
    /// Inertia of the body each joint moves, in that joint's frame (fixed children folded in).
    pub bodies: Vec<Inertia>,
    /// Every addressable frame (URDF link) on the chain.
    pub frames: Vec<Frame>,
    /// Index into `frames` of the tip frame.
    pub tip_frame: usize,
    /// Gravity in the base frame (default `(0, 0, -9.81)`).
    pub gravity: Vector3<f64>,
    /// Masses of the chain's links, for summaries.
    pub link_masses: Vec<LinkMass>,
    /// Links of the URDF left out of this model: the links of the dropped branches
    /// ([`Model::dropped_branches`]); their mass is ignored.
    pub excluded_links: Vec<String>,
    pub(crate) warnings: Vec<LoadWarning>,
    pub(crate) locked_branches: Vec<LockedBranch>,
    pub(crate) dropped_branches: Vec<DroppedBranch>,
    /// The lock positions the model was loaded with (`UrdfOptions::lock`), as given.
    pub(crate) lock_options: Vec<(String, f64)>,
}

impl Model {
    /// Number of moving joints (= coordinates = velocities).
    #[inline(always)]
    pub fn nq(&self) -> usize {
        self.joints.len()
    }

    /// Joint names in chain order.
    pub fn joint_names(&self) -> impl Iterator<Item = &str> {
        self.joints.iter().map(|j| j.name.as_str())
    }

    /// What the loader accepted with a warning (e.g. physically impossible inertias on
    /// the chain); empty for a clean file.
    pub fn warnings(&self) -> &[LoadWarning] {
        &self.warnings
    }

    /// The moving branches off the chain that the model carries locked, with their mass.
    pub fn locked_branches(&self) -> &[LockedBranch] {
        &self.locked_branches
    }

    /// The branches left out of the model on request, with their mass.
    pub fn dropped_branches(&self) -> &[DroppedBranch] {
        &self.dropped_branches
    }

    /// The lock positions the model was loaded with (`UrdfOptions::lock`, `--lock`), as
    /// given: with the base, tip and dropped branches, what loads it again from its URDF.
    pub fn lock_options(&self) -> &[(String, f64)] {
        &self.lock_options
    }

    /// Index of a moving joint by name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Index of a frame (URDF link) by name.
    pub fn frame_index(&self, name: &str) -> Option<usize> {
        self.frames.iter().position(|f| f.name == name)
    }

    /// The tip frame.
    pub fn tip(&self) -> &Frame {
        &self.frames[self.tip_frame]
    }

    /// Total mass carried by the moving joints (kg).
    pub fn total_moving_mass(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass).sum()
    }

    /// A copy with every body's mass and inertia multiplied by `scale` (e.g. 1.2 for the
    /// "20 % heavier than the nominal model" true arm of a simulation).
    pub fn with_scaled_inertias(&self, scale: f64) -> Result<Model, DynamicsError> {
        self.with_body_scales(&vec![scale; self.nq()])
    }

    /// A copy with body `i`'s mass and inertia (about the joint frame) multiplied by
    /// `scales[i]`. Scaling mass and inertia together keeps the centre of mass in place.
    pub fn with_body_scales(&self, scales: &[f64]) -> Result<Model, DynamicsError> {
        if scales.len() != self.nq() {
            return Err(DynamicsError::InvalidArgument(format!(
                "{} body scales given for a model with {} joints",
                scales.len(),
                self.nq()
            )));
        }
        if let Some(s) = scales.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
            return Err(DynamicsError::InvalidArgument(format!(
                "body scale {s} is not a positive finite number"
            )));
        }
        let mut out = self.clone();
        for (body, s) in out.bodies.iter_mut().zip(scales) {
            body.mass *= s;
            body.first_moment *= *s;
            body.rotational *= *s;
        }
        for lm in &mut out.link_masses {
            if let Some(j) = lm.joint {
                lm.mass *= scales[j];
            }
        }
        for branch in &mut out.locked_branches {
            if let Some(j) = branch.carried_by {
                branch.mass *= scales[j];
            }
        }
        Ok(out)
    }

    /// A copy carrying `payload` rigidly at the tip frame.
    pub fn with_payload(&self, payload: &Payload) -> Result<Model, DynamicsError> {
        let ok = payload.mass.is_finite()
            && payload.mass >= 0.0
            && payload.com.iter().all(|v| v.is_finite())
            && payload.inertia.iter().all(|v| v.is_finite());
        if !ok {
            return Err(DynamicsError::InvalidArgument(
                "payload mass must be finite and non-negative, com and inertia finite".into(),
            ));
        }
        let tip = self.tip().clone();
        let Some(joint) = tip.parent_joint else {
            return Err(DynamicsError::InvalidArgument(format!(
                "the tip frame '{}' is fixed to the base: a payload there moves nothing",
                tip.name
            )));
        };
        let local = Inertia::from_com(payload.mass, payload.com, payload.inertia);
        let mut out = self.clone();
        out.bodies[joint] = out.bodies[joint].add(&local.transformed(&tip.placement));
        out.link_masses.push(LinkMass {
            link: format!("payload@{}", tip.name),
            mass: payload.mass,
            joint: Some(joint),
        });
        Ok(out)
    }

    /// Lower and upper position limits per joint.
    pub fn position_limits(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.joints.iter().map(|j| (j.limits.lower, j.limits.upper))
    }

    /// Effort limit per joint (infinite when the URDF gives none).
    pub fn effort_limits(&self) -> impl Iterator<Item = f64> + '_ {
        self.joints.iter().map(|j| j.limits.effort)
    }
}
