//! The per-period contact and collision flags and the touched part of the chain.

use super::floor::ContactFloor;
use crate::error::ConfigError;

/// The detector's output for one control period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactState {
    /// Some joint's estimate is above its contact level (with hysteresis).
    pub contact: bool,
    /// Some joint's estimate is above its collision level (with hysteresis).
    pub collision: bool,
    /// The last joint (chain order, from 0) whose estimate is significant, i.e. above its
    /// contact level with hysteresis: a force on a link loads the joints before it only, so
    /// the touched link is this joint's child link or one after it; -1 when none.
    pub link: i32,
}

impl Default for ContactState {
    /// No contact, no collision, no link (-1).
    fn default() -> Self {
        ContactState {
            contact: false,
            collision: false,
            link: -1,
        }
    }
}

/// Per-joint hysteresis on the estimate against a [`ContactFloor`]'s levels (docs/method.md
/// section 5, "Contact"). Allocation-free and panic-free after construction.
#[derive(Clone, Debug)]
pub struct ContactDetector {
    floor: ContactFloor,
    contact: Vec<bool>,
    collision: Vec<bool>,
    state: ContactState,
}

impl ContactDetector {
    /// A detector with `floor`'s levels (checked).
    pub fn new(floor: &ContactFloor) -> Result<Self, ConfigError> {
        floor.validate()?;
        let n = floor.dof();
        Ok(ContactDetector {
            floor: floor.clone(),
            contact: vec![false; n],
            collision: vec![false; n],
            state: ContactState::default(),
        })
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.contact.len()
    }

    /// The floor it uses.
    pub fn floor(&self) -> &ContactFloor {
        &self.floor
    }

    /// The state of the last update.
    pub fn state(&self) -> ContactState {
        self.state
    }

    /// Joint `i`'s contact flag after the last update (false outside the chain).
    pub fn joint_contact(&self, i: usize) -> bool {
        self.contact.get(i).copied().unwrap_or(false)
    }

    /// Back to no contact.
    pub fn reset(&mut self) {
        self.contact.iter_mut().for_each(|c| *c = false);
        self.collision.iter_mut().for_each(|c| *c = false);
        self.state = ContactState::default();
    }

    /// One control period: the estimate (N m, docs/method.md's sign) and the measured
    /// velocity and acceleration that set the levels. Arguments of the wrong length leave
    /// the state as it was; a joint whose values are not finite keeps its flags.
    pub fn update(
        &mut self,
        external_torque_estimate: &[f64],
        qdot: &[f64],
        qddot: &[f64],
    ) -> ContactState {
        let n = self.dof();
        if external_torque_estimate.len() != n || qdot.len() != n || qddot.len() != n {
            return self.state;
        }
        let release = self.floor.release_fraction;
        let mut state = ContactState::default();
        for i in 0..n {
            let (e, v, a) = (external_torque_estimate[i], qdot[i], qddot[i]);
            if e.is_finite() && v.is_finite() && a.is_finite() {
                let scale = self.floor.scale(i, v, a);
                let size = e.abs();
                self.contact[i] = hysteresis(
                    self.contact[i],
                    size,
                    self.floor.contact_thresholds[i] * scale,
                    release,
                );
                self.collision[i] = hysteresis(
                    self.collision[i],
                    size,
                    self.floor.collision_thresholds[i] * scale,
                    release,
                );
            }
            if self.contact[i] || self.collision[i] {
                state.contact = true;
                state.link = i as i32;
            }
            state.collision |= self.collision[i];
        }
        self.state = state;
        state
    }
}

/// Raised above `level`, released below `release * level`.
#[inline]
fn hysteresis(on: bool, size: f64, level: f64, release: f64) -> bool {
    if on {
        size >= release * level
    } else {
        size > level
    }
}
