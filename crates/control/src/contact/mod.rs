//! Contact and collision detection on an external-torque estimate (issue 31; docs/method.md
//! section 5, "Contact"): a per-joint noise floor calibrated on free motion that the
//! identification did not fit, for a false-alarm rate the user states.
//!
//! * [`calibrate_contact`]: the floor from held-out free-motion estimates (every output is a
//!   false torque there). Per joint, the estimate is divided by its spread as a function of
//!   the joint's speed and acceleration and its nearness to a reversal; the excursions of that normalised estimate above a
//!   level are counted as events (a rising edge with the detector's hysteresis, never
//!   samples), and the tail of the per-event peak distribution (generalised Pareto, shape
//!   kept >= 0) is extrapolated to the level whose event rate is the user's.
//! * [`ContactFloor`]: the thresholds (contact, collision, their growth with speed and
//!   acceleration and their drop away from rest, the hysteresis) and what they were calibrated from, saved as a versioned,
//!   checksummed file.
//! * [`ContactDetector`]: per control period, `contact`, `collision` and the last joint whose
//!   estimate is significant (a force on a link loads the joints before it only);
//!   allocation-free and panic-free.
//! * [`soft_deadband`]: the admittance's deadband with a smooth knee (item 3).

mod calibrate;
mod deadband;
mod detector;
mod file;
mod floor;
mod spread;
mod tail;

pub use calibrate::{calibrate_contact, calibrate_contact_with, ContactCalibrationConfig};
pub(crate) use deadband::checked_deadband;
pub use deadband::{soft_deadband, DEADBAND_KNEE};
pub use detector::{ContactDetector, ContactState};
pub use file::{CONTACT_FLOOR_FORMAT, CONTACT_FLOOR_FORMAT_VERSION};
pub use floor::{ContactCalibration, ContactFloor};
pub use spread::LevelShape;
