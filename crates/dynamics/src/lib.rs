//! Rigid-body dynamics of serial robot arms loaded from URDF.
//!
//! An immutable [`Model`] is built once from a URDF (a chain between a base and a tip
//! link); a mutable [`Data`] workspace is built once from it and passed to every
//! algorithm, which writes its result into `Data` and returns a reference to it. After
//! construction no algorithm allocates, performs I/O or panics: argument lengths are
//! checked and reported as [`DimensionError`].
//!
//! Conventions: SI units; results in the base frame; 6-vectors (Jacobian rows,
//! wrenches, `Jdot qdot`) put the linear part first; gravity `(0, 0, -9.81)` unless
//! [`Model::gravity`] is changed. `M(q) qddot + C(q, qdot) qdot + G(q) = tau` is docs/method.md
//! eq. 1 without friction, deadzone or environment (those belong to the simulator).
//!
//! ```
//! use admittance_dynamics::{Model, Data, rnea, crba};
//! let model = Model::from_urdf_file("../../models/baxter_left_arm.urdf".as_ref(), Some("base"), Some("left_hand")).unwrap();
//! let mut data = Data::new(&model);
//! let q = [0.0, -0.5, 0.0, 1.0, 0.0, 0.5, 0.0];
//! let tau = rnea(&model, &mut data, &q, &[0.0; 7], &[0.0; 7]).unwrap().clone();
//! let m = crba(&model, &mut data, &q).unwrap();
//! assert!(m[(0, 0)] > 0.0 && tau.iter().all(|t| t.is_finite()));
//! ```
//!
//! Real descriptions carry more than the arm: grippers, heads, other arms. They load:
//! branches off the chain are carried locked (see [`UrdfOptions`] and
//! [`Model::from_urdf_file_with`]), and what the loader accepted with a warning is in
//! [`Model::warnings`].
#![warn(missing_docs)]

pub mod algorithms;
mod data;
mod error;
mod fingerprint;
mod identification;
mod model;
mod parallel;
pub mod spatial;
mod urdf;
mod wrapped_angles;

pub use algorithms::aba::{aba, aba_with_tip_wrench};
pub use algorithms::coriolis::coriolis_matrix;
pub use algorithms::crba::crba;
pub use algorithms::energy::{kinetic_energy, potential_energy};
pub use algorithms::jacobian::{frame_jacobian, frame_jdot_qdot, tip_jacobian, tip_jdot_qdot};
pub use algorithms::kinematics::{forward_kinematics, update_frame_placements};
pub use algorithms::mass_and_bias::{bias_and_gravity, mass_matrix_and_bias};
pub use algorithms::momentum::momentum_observer_terms;
pub use algorithms::regressor::{
    inertial_parameters, joint_torque_regressor, with_inertial_parameters, PARAMETERS_PER_BODY,
};
pub use algorithms::rnea::{gravity_torque, nonlinear_effects, rnea, rnea_with_tip_wrench};
pub use data::Data;
pub use error::{DimensionError, DynamicsError, LoadWarning, UrdfError};
pub use identification::{
    beyond_training_range, beyond_training_range_of, beyond_training_speed, excitation,
    faster_than_training, identify, identify_payload, is_physically_consistent,
    outside_training_range, AccelerationGains, BaseParameters, Excitation, ExcitationSettings,
    FourierSeries, Identification, IdentificationFile, IdentificationSettings,
    IdentificationSummary, JointTerms, LimitUse, RangeExcursion, Samples, SpeedExcursion,
    COULOMB_WIDTH_CANDIDATES, DEFAULT_EXCITATION_RANGE, DEFAULT_LIMIT_FRACTION,
    DEFAULT_VELOCITY_LIMIT, FIT_ACCELERATION_HZ, IDENTIFICATION_FORMAT,
    IDENTIFICATION_FORMAT_VERSION, TRAINING_RANGE_MARGIN, TRAINING_SPEED_MARGIN,
};
pub use model::{
    DroppedBranch, Frame, Joint, JointKind, JointLimits, LinkMass, LockedBranch, Model, Payload,
};
pub use parallel::parallel_map;
pub use spatial::{Force, Inertia, Motion, Transform};
pub use urdf::UrdfOptions;
pub use wrapped_angles::{unwrap_turns, IMPLAUSIBLE_JOINT_SPEED};

impl Model {
    /// Loads the chain between `base` (default: the root link) and `tip` (default: the
    /// arm's hand, see [`Model::from_urdf_file_with`]) from a URDF file, with the default
    /// [`UrdfOptions`].
    pub fn from_urdf_file(
        path: &std::path::Path,
        base: Option<&str>,
        tip: Option<&str>,
    ) -> Result<Model, DynamicsError> {
        urdf::load_file(path, &UrdfOptions::chain(base, tip))
    }

    /// Loads the chain from URDF text; `source` names the text in error messages.
    pub fn from_urdf_str(
        text: &str,
        source: &str,
        base: Option<&str>,
        tip: Option<&str>,
    ) -> Result<Model, DynamicsError> {
        urdf::load_str(text, source, &UrdfOptions::chain(base, tip))
    }

    /// Loads a model from a URDF file as `options` say.
    ///
    /// The **default tip** (when `options.tip` is `None`) is the arm's hand, found from the
    /// tree alone:
    /// 1. *end-effector joints* are set aside: mimic joints, joints a mimic joint follows,
    ///    and joints whose name contains `finger`, `gripper`, `jaw`, `thumb`, `knuckle` or
    ///    `hand` (any case), with their subtrees (unless that leaves no moving joint);
    /// 2. the *hand joint* is the moving joint of greatest depth (counted in moving joints
    ///    from the base); several at the greatest depth (two arms, four legs) is an error
    ///    listing the candidate tips;
    /// 3. the tip is the link behind the most fixed joints on the hand joint's body (a
    ///    TCP frame behind a flange), or the hand joint's child link when several tie.
    ///
    /// On a serial chain without end-effector joints this is its single leaf.
    pub fn from_urdf_file_with(
        path: &std::path::Path,
        options: &UrdfOptions,
    ) -> Result<Model, DynamicsError> {
        urdf::load_file(path, options)
    }

    /// Loads a model from URDF text as `options` say; `source` names the text in errors.
    pub fn from_urdf_str_with(
        text: &str,
        source: &str,
        options: &UrdfOptions,
    ) -> Result<Model, DynamicsError> {
        urdf::load_str(text, source, options)
    }
}
