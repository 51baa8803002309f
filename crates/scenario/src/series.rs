//! Time series a run records: the variant's `VARIANT.csv` (columns from
//! `admittance_runfolder::columns`), the free-motion data and the node weights.

use std::collections::HashMap;

use admittance_control::GaussianRbfLayer;
use admittance_runfolder::columns;

/// Named columns, rows in time order.
#[derive(Clone, Debug, Default)]
pub struct TimeSeries {
    /// Column names (the CSV header).
    pub columns: Vec<String>,
    /// Rows, each `columns.len()` long.
    pub rows: Vec<Vec<f64>>,
}

impl TimeSeries {
    /// Index of a column.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }
}

/// The columns of `VARIANT.csv`: `t`, the per-joint signals, `ee_error`, then `f.*` and
/// `f_hat.*` with dynamic nodes and `nodes.f` with the neural controller.
pub(crate) fn variant_columns(joints: &[String], with_f: bool, with_nodes: bool) -> Vec<String> {
    let mut out = vec![columns::TIME.to_string()];
    for prefix in columns::PER_JOINT {
        out.extend(columns::per_joint(prefix, joints));
    }
    out.push(columns::HAND_ERROR.into());
    if with_f {
        for prefix in [columns::F_TRUE, columns::F_ESTIMATE] {
            out.extend(columns::per_joint(prefix, joints));
        }
    }
    if with_nodes {
        out.push(columns::NODES_F.into());
    }
    out
}

/// The columns of free-motion data: `t, q.*, qdot.*, qddot.*, tau.*`.
pub(crate) fn free_motion_columns(joints: &[String]) -> Vec<String> {
    let mut out = vec![columns::TIME.to_string()];
    for prefix in columns::FREE_MOTION {
        out.extend(columns::per_joint(prefix, joints));
    }
    out
}

/// Sampling interval (s) of the node-weight series.
pub const NODE_WEIGHT_INTERVAL: f64 = 0.25;

/// Follows the f network's nodes by their centres (indices shift when nodes are
/// discarded) and samples their weight-row norms.
#[derive(Default)]
pub(crate) struct NodeWeightTrace {
    ids: HashMap<Vec<u64>, usize>,
    samples: Vec<(f64, Vec<(usize, f64)>)>,
}

impl NodeWeightTrace {
    pub fn sample(&mut self, t: f64, layer: &GaussianRbfLayer) {
        let mut row = Vec::with_capacity(layer.len());
        for i in 0..layer.len() {
            let (Some(centre), Some(w)) = (layer.centre(i), layer.weight_row(i)) else {
                continue;
            };
            let key: Vec<u64> = centre.iter().map(|c| c.to_bits()).collect();
            let next = self.ids.len();
            let id = *self.ids.entry(key).or_insert(next);
            row.push((id, w.iter().map(|x| x * x).sum::<f64>().sqrt()));
        }
        self.samples.push((t, row));
    }

    /// Columns `t, w.ID`: nodes numbered in the order they first appeared, `NaN` while a
    /// node does not exist.
    pub fn into_series(self) -> TimeSeries {
        let count = self.ids.len();
        let mut cols = vec![columns::TIME.to_string()];
        cols.extend((0..count).map(|id| format!("{}{id}", columns::NODE_WEIGHT_PREFIX)));
        let rows = self
            .samples
            .into_iter()
            .map(|(t, values)| {
                let mut row = vec![f64::NAN; count + 1];
                row[0] = t;
                for (id, v) in values {
                    row[id + 1] = v;
                }
                row
            })
            .collect();
        TimeSeries {
            columns: cols,
            rows,
        }
    }
}
