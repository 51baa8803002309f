//! `[contact]` in a run (issue 31): the contact floor, calibrated at the start on free
//! motion the identification did not fit (or read from a file), the detector on the
//! loop's estimate every control period, and what it did against the true external torque
//! ([`crate::contact_score`]).

use std::path::Path;

use admittance_control::{ContactDetector, ContactFloor, ContactState};
use admittance_dynamics::Model;

use crate::contact_score::{score, ContactMetrics, StepFlags};
use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::progress::RunOptions;
use crate::spec::Scenario;
use crate::training::{free_motion_data, IdentifiedNominal, SimulateData};

/// The floor of a run's `[contact]` table and where it came from; `None` without the table.
pub(crate) fn contact_floor(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    model: &Model,
    path: &Path,
    options: &RunOptions,
    simulate: SimulateData<'_>,
    identified: Option<&IdentifiedNominal>,
) -> Result<Option<ContactFloor>, ScenarioError> {
    let Some(spec) = &scenario.contact else {
        return Ok(None);
    };
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let resolve = |p: &Path| {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            path.parent().unwrap_or(Path::new(".")).join(p)
        }
    };
    if let Some(file) = &spec.floor {
        let file = resolve(file);
        let floor = ContactFloor::load(&file).map_err(|e| ctx.config_err("contact.floor", &e))?;
        if floor.dof() != joints.len() || (!floor.joints.is_empty() && floor.joints != joints) {
            return Err(ctx.err(
                "contact.floor",
                format!(
                    "{} is for the joints [{}], the arm has [{}]",
                    file.display(),
                    floor.joints.join(", "),
                    joints.join(", ")
                ),
                Some("calibrate a floor for this arm: admittance calibrate-contact"),
            ));
        }
        return Ok(Some(floor));
    }
    let Some(given) = &spec.calibration else {
        return Ok(None); // refused by the checks of [contact]
    };
    let Some(nominal) = identified else {
        return Err(ctx.err(
            "contact.calibration",
            "needs the identification the momentum observer runs on",
            Some("set observer.training.identify = true or observer.identification = FILE"),
        ));
    };
    let data = free_motion_data(
        ctx,
        path,
        "contact.calibration",
        given,
        &joints,
        options,
        simulate,
    )?;
    let observer = &scenario.observer;
    let estimates = crate::contact::momentum_estimates_at(
        &data,
        &nominal.identification,
        &observer.momentum,
        observer.input_filter_hz,
    )
    .and_then(|e| e.low_passed(observer.cutoff_hz))
    .map_err(|e| ctx.config_err("contact.calibration", &e))?;
    let mut floor = crate::contact::floor_of_estimates(
        std::slice::from_ref(&estimates),
        &joints,
        &nominal.identification,
        &observer.momentum,
        &spec.calibration_config(),
    )
    .map_err(|e| ctx.config_err("contact.calibration", &e))?;
    let origin = resolve(given).display().to_string();
    floor.source.insert("calibration".into(), origin.into());
    floor.source.insert(
        "identification".into(),
        nominal.path.display().to_string().into(),
    );
    floor
        .source
        .insert("estimate_cutoff_hz".into(), observer.cutoff_hz.into());
    floor
        .source
        .insert("input_filter_hz".into(), observer.input_filter_hz.into());
    floor.created_by = format!("admittance {}", env!("CARGO_PKG_VERSION"));
    Ok(Some(floor))
}

/// The detector of a run and the flags it raised, step by step.
pub(crate) struct ContactRun {
    detector: ContactDetector,
    state: ContactState,
    level: Vec<f64>,
    steps: Vec<StepFlags>,
    true_torque: Vec<f64>,
    window_level: Vec<f64>,
    reference_offset_max_abs: Vec<f64>,
}

impl ContactRun {
    /// A detector on `floor` (checked for the arm's joint count by [`contact_floor`]).
    pub fn new(floor: &ContactFloor) -> Result<Self, admittance_control::ConfigError> {
        let n = floor.dof();
        Ok(Self {
            detector: ContactDetector::new(floor)?,
            state: ContactState::default(),
            level: vec![0.0; n],
            steps: Vec::new(),
            true_torque: Vec::new(),
            window_level: Vec::new(),
            reference_offset_max_abs: vec![0.0; n],
        })
    }

    /// The floor.
    pub fn floor(&self) -> &ContactFloor {
        self.detector.floor()
    }

    /// One control period: the loop's estimate and the velocity and acceleration it saw.
    pub fn update(&mut self, estimate: &[f64], qdot: &[f64], qddot: &[f64]) {
        self.state = self.detector.update(estimate, qdot, qddot);
        let floor = self.detector.floor();
        for (i, l) in self.level.iter_mut().enumerate() {
            let (v, a) = (qdot.get(i).copied(), qddot.get(i).copied());
            let scale = match (v, a) {
                (Some(v), Some(a)) if v.is_finite() && a.is_finite() => floor.scale(i, v, a),
                _ => 1.0,
            };
            *l = floor.contact_thresholds[i] * scale;
        }
    }

    /// The flags of the last period and each joint's contact level.
    pub fn flags(&self) -> (ContactState, &[f64]) {
        (self.state, &self.level)
    }

    /// Keeps a step of the evaluation window for the scores: the true external torque,
    /// the compliant reference and the desired motion.
    pub fn in_window(&mut self, t: f64, true_torque: &[f64], q_r: &[f64], q_d: &[f64]) {
        self.steps.push(StepFlags {
            t,
            contact: self.state.contact,
            collision: self.state.collision,
            link: self.state.link,
        });
        self.true_torque.extend_from_slice(true_torque);
        self.window_level.extend_from_slice(&self.level);
        for ((m, r), d) in self.reference_offset_max_abs.iter_mut().zip(q_r).zip(q_d) {
            *m = m.max((r - d).abs());
        }
    }

    /// The scores of the window.
    pub fn finish(self) -> ContactMetrics {
        let floor = self.detector.floor();
        let mut m = score(
            &self.steps,
            &self.true_torque,
            &self.window_level,
            floor.dof(),
        );
        m.contact_promised_false_alarms_per_hour = floor.false_alarms_per_hour;
        m.contact_thresholds = floor.contact_thresholds.clone();
        m.collision_thresholds = floor.collision_thresholds.clone();
        m.reference_offset_max_abs = self.reference_offset_max_abs;
        m
    }
}
