//! What a model records of its making, applied to a [`BroadModel`]: setting and checking
//! the arm and the data settings (the types are in `provenance.rs`).

use super::error::BroadError;
use super::model::BroadModel;
use super::provenance::*;

impl BroadModel {
    /// Everything the model knows about how it was made.
    pub fn provenance(&self) -> &Provenance {
        &self.provenance
    }

    /// The arm the model was trained for, if recorded.
    pub fn arm(&self) -> Option<&ArmIdentity> {
        self.provenance.arm.as_ref()
    }

    /// Records the arm the model was trained for. Its joint count must match the
    /// model's outputs (one torque per joint).
    pub fn set_arm(&mut self, arm: ArmIdentity) -> Result<(), BroadError> {
        let n = arm.joints.len();
        if n != self.d_out {
            return Err(BroadError::Config(format!(
                "an arm of {n} joints does not fit a model with {} outputs",
                self.d_out
            )));
        }
        self.provenance.arm = Some(arm);
        Ok(())
    }

    /// Records how the data were prepared (checked with [`DataSettings::validate`]).
    pub fn set_data_settings(&mut self, settings: DataSettings) -> Result<(), BroadError> {
        settings.validate()?;
        self.provenance.data = Some(settings);
        Ok(())
    }

    /// Checks that the model was trained for `arm`: same joint names in the same order
    /// and the same fingerprint. A model that records no identity passes as
    /// [`ArmCheck::Unrecorded`]; a different arm is [`BroadError::ArmMismatch`], saying
    /// what differs.
    pub fn check_arm(&self, arm: &ArmIdentity) -> Result<ArmCheck, BroadError> {
        let Some(own) = &self.provenance.arm else {
            return Ok(ArmCheck::Unrecorded);
        };
        if let Some(d) = joint_differences(&own.joints, &arm.joints) {
            return Err(BroadError::ArmMismatch(d));
        }
        if own.fingerprint != arm.fingerprint {
            return Err(BroadError::ArmMismatch(format!(
                "the model was trained for another model of the arm with the same joint names \
                 (arm fingerprint {:016x}, this arm's is {:016x}): a joint's kind, axis, origin \
                 or limits, or a body's mass, centre of mass or inertia differ",
                own.fingerprint, arm.fingerprint
            )));
        }
        Ok(ArmCheck::Matches)
    }

    /// Checks only the joint names (for data that name their joints but carry no arm
    /// model, e.g. a free-motion CSV). As [`check_arm`](Self::check_arm) otherwise.
    pub fn check_joints<S: AsRef<str>>(&self, joints: &[S]) -> Result<ArmCheck, BroadError> {
        let Some(own) = &self.provenance.arm else {
            return Ok(ArmCheck::Unrecorded);
        };
        let given: Vec<String> = joints.iter().map(|j| j.as_ref().to_string()).collect();
        match joint_differences(&own.joints, &given) {
            Some(d) => Err(BroadError::ArmMismatch(d)),
            None => Ok(ArmCheck::Matches),
        }
    }

    /// Checks that the model's data settings are `expected` (a user of the model must
    /// condition its inputs the same way and expect the same target).
    /// [`BroadError::SettingsMismatch`] lists every difference; a model that records no
    /// settings passes as [`ArmCheck::Unrecorded`].
    pub fn check_data_settings(&self, expected: &DataSettings) -> Result<ArmCheck, BroadError> {
        let Some(own) = &self.provenance.data else {
            return Ok(ArmCheck::Unrecorded);
        };
        let diff = own.differences(expected);
        if diff.is_empty() {
            Ok(ArmCheck::Matches)
        } else {
            Err(BroadError::SettingsMismatch(format!(
                "the model was trained with {}",
                diff.join("; ")
            )))
        }
    }
}
