//! `[contact]`: contact and collision detection on the run's estimate (issue 31).
//!
//! ```toml
//! [contact]
//! calibration = "free_motion_validation.toml"  # free motion the identification did not fit
//! false_alarms_per_hour = 1.0                  # the promised rate of false contact events
//! deadband = true                              # the admittance ignores an estimate inside the floor
//! # floor = "contact_floor.json"               # instead of calibration: `admittance calibrate-contact`'s file
//! ```

use std::path::PathBuf;

use admittance_control::{ConfigError, ContactCalibrationConfig};
use admittance_loop::ObserverKind;
use serde::{Deserialize, Serialize};

use super::Scenario;

/// Where the run's contact floor comes from, and what it does.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Free motion the identification did not fit (a data scenario `.toml` or a free-motion
    /// CSV, relative to the scenario file): the floor is calibrated on the momentum
    /// observer's estimate over it at the start of the run. Exclusive with `floor`.
    #[serde(default)]
    pub calibration: Option<PathBuf>,
    /// A contact-floor file (`admittance calibrate-contact`), relative to the scenario file.
    /// Exclusive with `calibration`.
    #[serde(default)]
    pub floor: Option<PathBuf>,
    /// False contact events per hour the calibrated floor allows (default 1; the other
    /// calibration settings keep `ContactCalibrationConfig`'s defaults).
    #[serde(default = "default_rate")]
    pub false_alarms_per_hour: f64,
    /// The admittance takes the floor's contact thresholds as a deadband on the estimate
    /// (docs/method.md section 2, "Deadband"). Default false.
    #[serde(default)]
    pub deadband: bool,
}

fn default_rate() -> f64 {
    ContactCalibrationConfig::default().false_alarms_per_hour
}

impl ContactSpec {
    /// The calibration settings of this table.
    pub fn calibration_config(&self) -> ContactCalibrationConfig {
        ContactCalibrationConfig {
            false_alarms_per_hour: self.false_alarms_per_hour,
            ..ContactCalibrationConfig::default()
        }
    }
}

impl Scenario {
    /// The checks of `[contact]`.
    pub(super) fn validate_contact(&self, out: &mut Vec<ConfigError>) {
        let Some(c) = &self.contact else { return };
        match (&c.calibration, &c.floor) {
            (None, None) => out.push(
                ConfigError::new("contact", "names neither `calibration` nor `floor`").hint(
                    "calibration = \"FREE_MOTION.toml\" (free motion the identification did not fit), or floor = \"FILE\"",
                ),
            ),
            (Some(_), Some(_)) => out.push(
                ConfigError::new("contact.floor", "goes with `calibration`: give one of them")
                    .hint("`floor` reads a floor made elsewhere; `calibration` makes one"),
            ),
            _ => {}
        }
        if let Err(e) = c.calibration_config().validate() {
            out.push(e.within("contact"));
        }
        if c.calibration.is_some() && self.observer.kind != ObserverKind::Momentum {
            out.push(
                ConfigError::new(
                    "contact.calibration",
                    "calibrates the momentum observer's floor, and observer.kind is another",
                )
                .hint("set observer.kind = \"momentum\", or give a floor made for this observer"),
            );
        }
        if c.deadband && self.admittance.is_none() && self.task_admittance.is_none() {
            out.push(ConfigError::new(
                "contact.deadband",
                "needs an [admittance] or [task_admittance] table",
            ));
        }
    }
}
