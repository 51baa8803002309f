//! What a model knows about itself: the arm it was trained for and every setting that
//! made it (docs/outputs.md, "Model files"). [`fit`](super::fit) and
//! `BroadModel::grow` record their own settings; the caller adds what only it knows
//! (the arm, the input conditioning, the validation split, the target) with
//! `BroadModel::set_arm` and `BroadModel::set_data_settings`. Every user of a model
//! checks them: `BroadModel::check_arm`, `BroadModel::check_joints`,
//! `BroadModel::check_data_settings`.

use super::config::WidthRule;
use super::error::BroadError;
use serde::{Deserialize, Serialize};

/// Which arm a model was trained for: the joint names in chain order and the arm model's
/// fingerprint (`admittance_dynamics::Model::fingerprint`, a hash of the joints' kinds,
/// axes, origins and limits and every body's mass, centre of mass and inertia).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ArmIdentity {
    /// Joint names, chain order (the order of the network's inputs and outputs).
    pub joints: Vec<String>,
    /// Fingerprint of the arm's model (written as 16 hex digits in the file).
    #[serde(with = "hex_u64")]
    pub fingerprint: u64,
}

impl ArmIdentity {
    /// From joint names and a fingerprint.
    pub fn new<S: Into<String>>(joints: impl IntoIterator<Item = S>, fingerprint: u64) -> Self {
        Self {
            joints: joints.into_iter().map(Into::into).collect(),
            fingerprint,
        }
    }
}

mod hex_u64 {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{v:016x}"))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        let text = String::deserialize(d)?;
        u64::from_str_radix(&text, 16).map_err(|_| {
            serde::de::Error::custom(format!("fingerprint {text:?} is not 16 hex digits"))
        })
    }
}

/// What the network learned to predict.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum TrainingTarget {
    /// The free-motion torque `tau(q, q', q'')` (observer kind `learned`, docs/method.md
    /// section 5, eq. 19).
    FreeMotionTorque,
    /// What the nominal model misses, `tau - RNEA_nominal(q, q', q'')` (observer kind
    /// `hybrid`); the nominal model is the arm's model with every body's mass and inertia
    /// multiplied by `nominal_inertia_scale`.
    NominalResidual {
        /// Scale of the nominal model's masses and inertias.
        nominal_inertia_scale: f64,
    },
    /// What an identified model misses, `tau - ident.predict(q, q', q'')` (the hybrid
    /// observer on an identification file of `admittance identify`, `admittance train
    /// --nominal`).
    IdentifiedResidual {
        /// FNV-1a 64 of the identification file's bytes (written as 16 hex digits): which
        /// identification the residual belongs to.
        #[serde(with = "hex_u64")]
        checksum: u64,
    },
}

impl std::fmt::Display for TrainingTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TrainingTarget::FreeMotionTorque => write!(f, "the free-motion torque"),
            TrainingTarget::NominalResidual {
                nominal_inertia_scale,
            } => write!(
                f,
                "the residual of the nominal model (inertia scale {nominal_inertia_scale})"
            ),
            TrainingTarget::IdentifiedResidual { checksum } => write!(
                f,
                "the residual of the identified model (identification file checksum {checksum:016x})"
            ),
        }
    }
}

/// Which rows chose the ridge parameter and measured the validation error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ValidationSplit {
    /// The last `fraction` of the rows of the training data (`admittance train
    /// --validation-fraction`); the network was fitted on the rows before them.
    TrailingFraction {
        /// Fraction of the rows held out, in (0, 1).
        fraction: f64,
    },
    /// A separate data set (a scenario's `[observer.training] validation`, `admittance
    /// train --validation`).
    SeparateData,
    /// Blocked cross-validation over `folds` contiguous stretches of the training rows
    /// (each scored by a fit on the others); the network was fitted on all of them.
    BlockedCrossValidation {
        /// Number of stretches K (>= 2).
        folds: usize,
    },
    /// No validation data (one ridge parameter given).
    NoValidation,
}

impl std::fmt::Display for ValidationSplit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ValidationSplit::TrailingFraction { fraction } => {
                write!(f, "the last {fraction} of the rows")
            }
            ValidationSplit::SeparateData => write!(f, "a separate data set"),
            ValidationSplit::BlockedCrossValidation { folds } => {
                write!(f, "blocked cross-validation over {folds} stretches")
            }
            ValidationSplit::NoValidation => write!(f, "no validation data"),
        }
    }
}

/// How the caller prepared the rows the network was fitted on; [`fit`](super::fit) cannot
/// know it, so the caller records it with `BroadModel::set_data_settings`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataSettings {
    /// Cut-off (Hz) of the observer's input conditioning (`admittance_loop::InputConditioner`,
    /// `--input-filter-hz`, `observer.input_filter_hz`); 0: the columns as recorded. The
    /// observer must be fed the same conditioning at run time.
    pub input_filter_hz: f64,
    /// Which rows validated the fit.
    pub validation: ValidationSplit,
    /// What the network predicts.
    pub target: TrainingTarget,
}

impl DataSettings {
    /// Checks the values' domains.
    pub fn validate(&self) -> Result<(), BroadError> {
        if !(self.input_filter_hz.is_finite() && self.input_filter_hz >= 0.0) {
            return Err(BroadError::Config(format!(
                "input filter {} Hz must be finite and >= 0",
                self.input_filter_hz
            )));
        }
        if let ValidationSplit::TrailingFraction { fraction } = self.validation {
            if !(fraction > 0.0 && fraction < 1.0) {
                return Err(BroadError::Config(format!(
                    "validation fraction {fraction} must be in (0, 1)"
                )));
            }
        }
        if let ValidationSplit::BlockedCrossValidation { folds } = self.validation {
            if folds < 2 {
                return Err(BroadError::Config(format!(
                    "cross-validation folds {folds} must be >= 2"
                )));
            }
        }
        if let TrainingTarget::NominalResidual {
            nominal_inertia_scale: s,
        } = self.target
        {
            if !(s.is_finite() && s > 0.0) {
                return Err(BroadError::Config(format!(
                    "nominal inertia scale {s} must be finite and > 0"
                )));
            }
        }
        Ok(())
    }

    /// The settings of `self` that differ from `other`, one phrase each (empty if none).
    pub fn differences(&self, other: &DataSettings) -> Vec<String> {
        let mut out = Vec::new();
        if self.input_filter_hz.to_bits() != other.input_filter_hz.to_bits() {
            out.push(format!(
                "input filter {} Hz, not {} Hz",
                self.input_filter_hz, other.input_filter_hz
            ));
        }
        if self.validation != other.validation {
            out.push(format!(
                "validation on {}, not on {}",
                self.validation, other.validation
            ));
        }
        if self.target != other.target {
            out.push(format!("target {}, not {}", self.target, other.target));
        }
        out
    }
}

/// How the enhancement nodes' centres and widths were chosen (k-means++ seeding on a
/// random subsample, [`BroadConfig`](super::BroadConfig)).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CentreSettings {
    /// Rows of the subsample the centres are drawn from.
    pub centre_subsample: usize,
    /// Seed of the generator.
    pub seed: u64,
    /// Width rule.
    pub widths: WidthRule,
}

/// The fit's own settings, recorded by [`fit`](super::fit) and
/// [`fit_with_nodes`](super::fit_with_nodes). The friction features and the chosen
/// ridge parameter are part of the model itself (`BroadModel::friction`,
/// `BroadModel::lambda_rel`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitSettings {
    /// Enhancement nodes of the fit (before any growth).
    pub nodes: usize,
    /// How the centres were placed; `None` when they were given (`fit_with_nodes`).
    pub centres: Option<CentreSettings>,
    /// Candidate relative ridge parameters.
    pub lambda_grid: Vec<f64>,
    /// Training rows.
    pub training_rows: usize,
    /// Validation rows (0 without validation data).
    pub validation_rows: usize,
    /// Outputs set to zero because they did not beat zero on unseen motion
    /// (`BroadConfig::zero_unhelpful_outputs`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub zeroed_outputs: Vec<usize>,
}

/// One incremental growth (`BroadModel::grow`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrowthRecord {
    /// Nodes added.
    pub nodes_added: usize,
    /// How the new centres were placed; `None` when they were given.
    pub centres: Option<CentreSettings>,
}

/// Everything a model knows about how it was made. Files of format version 1 know none
/// of it (every field `None` or empty).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Provenance {
    /// The arm it was trained for.
    pub arm: Option<ArmIdentity>,
    /// How the data were prepared.
    pub data: Option<DataSettings>,
    /// The fit.
    pub fit: Option<FitSettings>,
    /// The growths since the fit, oldest first.
    pub growth: Vec<GrowthRecord>,
}

/// The outcome of a successful identity check.
#[must_use]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArmCheck {
    /// The model records an identity and it matches.
    Matches,
    /// The model records no identity (a file of format version 1, or a model fitted in
    /// memory without `BroadModel::set_arm`): nothing could be checked; callers should
    /// say so.
    Unrecorded,
}

pub(super) fn joint_differences(model: &[String], given: &[String]) -> Option<String> {
    if model == given {
        return None;
    }
    let detail = if model.len() != given.len() {
        format!("{} joints, not {}", given.len(), model.len())
    } else {
        let k = model
            .iter()
            .zip(given)
            .position(|(a, b)| a != b)
            .unwrap_or(0);
        format!("joint {} is `{}`, not `{}`", k + 1, given[k], model[k])
    };
    Some(format!(
        "the model was trained for the joints [{}], these are [{}] ({detail})",
        model.join(", "),
        given.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn provenance_round_trips_through_json() {
        let p = Provenance {
            arm: Some(ArmIdentity::new(["a", "b"], 0x0123_4567_89ab_cdef)),
            data: Some(DataSettings {
                input_filter_hz: 10.0,
                validation: ValidationSplit::TrailingFraction { fraction: 0.2 },
                target: TrainingTarget::NominalResidual {
                    nominal_inertia_scale: 0.1 + 0.2,
                },
            }),
            fit: Some(FitSettings {
                nodes: 40,
                centres: Some(CentreSettings {
                    centre_subsample: 20_000,
                    seed: u64::MAX,
                    widths: WidthRule::Knn { k: 8, scale: 2.0 },
                }),
                lambda_grid: vec![1e-10, 1.0 / 3.0],
                training_rows: 10,
                validation_rows: 2,
                zeroed_outputs: vec![2],
            }),
            growth: vec![GrowthRecord {
                nodes_added: 3,
                centres: None,
            }],
        };
        let text = serde_json::to_string(&p).unwrap();
        assert!(
            text.contains("\"fingerprint\":\"0123456789abcdef\""),
            "{text}"
        );
        assert!(text.contains("\"kind\":\"trailing_fraction\""), "{text}");
        let back: Provenance = serde_json::from_str(&text).unwrap();
        assert_eq!(back, p);
        // Bit-exact floats.
        let Some(DataSettings {
            target:
                TrainingTarget::NominalResidual {
                    nominal_inertia_scale,
                },
            ..
        }) = back.data
        else {
            panic!()
        };
        assert_eq!(nominal_inertia_scale.to_bits(), (0.1f64 + 0.2).to_bits());
        let bad = text.replace("0123456789abcdef", "xyz");
        assert!(serde_json::from_str::<Provenance>(&bad).is_err());
    }

    #[test]
    fn data_settings_differences_name_each_setting() {
        let a = DataSettings {
            input_filter_hz: 10.0,
            validation: ValidationSplit::TrailingFraction { fraction: 0.2 },
            target: TrainingTarget::FreeMotionTorque,
        };
        assert!(a.differences(&a).is_empty());
        let b = DataSettings {
            input_filter_hz: 0.0,
            validation: ValidationSplit::SeparateData,
            target: TrainingTarget::NominalResidual {
                nominal_inertia_scale: 1.2,
            },
        };
        let d = a.differences(&b);
        assert_eq!(d.len(), 3, "{d:?}");
        assert!(d[0].contains("input filter 10 Hz, not 0 Hz"), "{d:?}");
        assert!(d[2].contains("inertia scale 1.2"), "{d:?}");
        assert!(DataSettings {
            input_filter_hz: f64::NAN,
            ..a
        }
        .validate()
        .is_err());
        assert!(DataSettings {
            validation: ValidationSplit::TrailingFraction { fraction: 1.0 },
            ..a
        }
        .validate()
        .is_err());
    }

    /// The new variants round-trip; files written before them still read.
    #[test]
    fn identified_residual_and_cross_validation_round_trip() {
        let d = DataSettings {
            input_filter_hz: 4.0,
            validation: ValidationSplit::BlockedCrossValidation { folds: 5 },
            target: TrainingTarget::IdentifiedResidual {
                checksum: 0xfedc_ba98_7654_3210,
            },
        };
        let text = serde_json::to_string(&d).unwrap();
        assert!(
            text.contains("\"kind\":\"blocked_cross_validation\",\"folds\":5"),
            "{text}"
        );
        assert!(text.contains("\"checksum\":\"fedcba9876543210\""), "{text}");
        assert_eq!(serde_json::from_str::<DataSettings>(&text).unwrap(), d);
        let old = r#"{"input_filter_hz":0.0,"validation":{"kind":"trailing_fraction","fraction":0.2},"target":{"kind":"free_motion_torque"}}"#;
        assert!(serde_json::from_str::<DataSettings>(old).is_ok());
        assert!(DataSettings {
            validation: ValidationSplit::BlockedCrossValidation { folds: 1 },
            ..d
        }
        .validate()
        .is_err());
        assert!(d.target.to_string().contains("fedcba9876543210"));
    }

    #[test]
    fn joint_differences_say_which_joint() {
        let m: Vec<String> = ["a", "b", "c"].map(String::from).into();
        assert_eq!(joint_differences(&m, &m), None);
        let d = joint_differences(&m, &["a".into(), "x".into(), "c".into()]).unwrap();
        assert!(d.contains("joint 2 is `x`, not `b`"), "{d}");
        let d = joint_differences(&m, &["a".into()]).unwrap();
        assert!(d.contains("1 joints, not 3"), "{d}");
    }
}
