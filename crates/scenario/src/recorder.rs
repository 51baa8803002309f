//! The time series a variant records: `VARIANT.csv` every `output.decimation` steps and,
//! with `[record] free_motion_csv`, the free-motion data at every control sample.

use admittance_loop::Measurement;
use admittance_sim::StepRecord;

use crate::hand::hand_columns;
use crate::series::{free_motion_columns, variant_columns, TimeSeries};

/// The series being recorded.
pub(crate) struct Recorder {
    pub series: TimeSeries,
    pub free_motion: Option<TimeSeries>,
    previous_filtered_torque: Vec<f64>,
    decimation: usize,
    with_coverage: bool,
    with_contact: bool,
}

/// One row's values beyond the per-joint signals.
pub(crate) struct Row<'a> {
    pub t: f64,
    pub q_d: &'a [f64],
    pub q_r: &'a [f64],
    pub q: &'a [f64],
    pub qdot: &'a [f64],
    pub measurement: &'a Measurement,
    pub torque: &'a [f64],
    pub record: &'a StepRecord,
    pub estimate: &'a [f64],
    pub ee_error: f64,
    /// `f` and `f_hat` (dynamic nodes).
    pub f: Option<(&'a [f64], &'a [f64])>,
    /// The f network's node count (neural controller).
    pub nodes: Option<usize>,
    /// `f_hand`, `f_hand_hat`, `x_hand`, `x_hand_r`, `x_hand_d` (task-space runs).
    pub hand: Option<[&'a [f64]; 5]>,
    /// The observer's coverage of its input (with [`Recorder::record_coverage`]).
    pub coverage: Option<f64>,
    /// The contact flags and each joint's contact level (with [`Recorder::record_contact`]).
    pub contact: Option<(admittance_control::ContactState, &'a [f64])>,
}

impl Recorder {
    /// The columns for the arm's `joints` and what the run has.
    pub fn new(
        joints: &[String],
        decimation: usize,
        free_motion: bool,
        with_f: bool,
        with_nodes: bool,
        with_hand: bool,
    ) -> Self {
        let mut columns = variant_columns(joints, with_f, with_nodes);
        if with_hand {
            columns.extend(hand_columns());
        }
        Self {
            series: TimeSeries {
                columns,
                rows: Vec::new(),
            },
            free_motion: free_motion.then(|| TimeSeries {
                columns: free_motion_columns(joints),
                rows: Vec::new(),
            }),
            previous_filtered_torque: vec![0.0; joints.len()],
            decimation,
            with_coverage: false,
            with_contact: false,
        }
    }

    /// Free-motion data: what the sensors saw, with the filtered command delayed by one
    /// sample to match `qddot`'s delay (docs/method.md section 7, docs/outputs.md).
    pub fn sensed(&mut self, t: f64, m: &Measurement) {
        if let Some(fm) = self.free_motion.as_mut() {
            let mut row = Vec::with_capacity(1 + 4 * m.q.len());
            row.push(t);
            for v in [
                &m.q_filtered[..],
                &m.qdot,
                &m.qddot,
                &self.previous_filtered_torque,
            ] {
                row.extend_from_slice(v);
            }
            fm.rows.push(row);
        }
        self.previous_filtered_torque
            .copy_from_slice(&m.tau_filtered);
    }

    /// Adds the column `estimate_coverage` (an observer with a learned part that reports
    /// where its training data end; docs/outputs.md) as the last column.
    pub fn record_coverage(&mut self) {
        self.series
            .columns
            .push(admittance_runfolder::columns::ESTIMATE_COVERAGE.into());
        self.with_coverage = true;
    }

    /// Adds the columns `contact`, `collision`, `contact_link` and `contact_level.*`
    /// (`[contact]`; docs/outputs.md) after the others.
    pub fn record_contact(&mut self, joints: &[String]) {
        use admittance_runfolder::columns;
        let c = &mut self.series.columns;
        c.extend([columns::CONTACT, columns::COLLISION, columns::CONTACT_LINK].map(String::from));
        c.extend(columns::per_joint(columns::CONTACT_LEVEL, joints));
        self.with_contact = true;
    }

    /// Whether step `k` writes a row.
    pub fn wants(&self, k: usize) -> bool {
        k.is_multiple_of(self.decimation)
    }

    /// A row of `VARIANT.csv`.
    pub fn row(&mut self, r: &Row<'_>) {
        let mut row = Vec::with_capacity(self.series.columns.len());
        row.push(r.t);
        for v in [
            r.q_d,
            r.q_r,
            r.q,
            r.qdot,
            &r.measurement.q[..],
            r.torque,
            &r.record.applied,
            &r.record.tau_ext,
            r.estimate,
        ] {
            row.extend_from_slice(v);
        }
        row.push(r.ee_error);
        if let Some((f, f_hat)) = r.f {
            row.extend_from_slice(f);
            row.extend_from_slice(f_hat);
        }
        if let Some(nodes) = r.nodes {
            row.push(nodes as f64);
        }
        if let Some(hand) = r.hand {
            for v in hand {
                row.extend_from_slice(v);
            }
        }
        if self.with_coverage {
            row.push(r.coverage.unwrap_or(f64::NAN));
        }
        if self.with_contact {
            let n = self.previous_filtered_torque.len();
            match r.contact {
                Some((s, level)) => {
                    row.push(f64::from(u8::from(s.contact)));
                    row.push(f64::from(u8::from(s.collision)));
                    row.push(f64::from(s.link));
                    row.extend_from_slice(level);
                }
                None => row.extend(std::iter::repeat_n(f64::NAN, 3 + n)),
            }
        }
        self.series.rows.push(row);
    }
}
