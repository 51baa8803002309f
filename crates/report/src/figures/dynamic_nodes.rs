//! Experiment C, dynamic RBF nodes (scenario `dynamic_nodes`): Figs 21-26 and the node
//! count (S1). The discard and growth times are where `nodes.f` first falls and rises.
//! The weight figures show hundreds of nodes: the few most active are drawn as lines over
//! a band that spans the rest.

use admittance_runfolder::{columns, files};

use super::common::{compared, extra, figure, joint0, joint_col, line, panel, planned, time};
use super::model::{Band, Figure, Marker, Panel, Planned};
use crate::folder::{RunFolder, Variant};
use crate::table::Table;

/// Nodes drawn as lines in a weight figure; the others form the band.
const HIGHLIGHTED: usize = 6;

/// Which nodes a weight figure shows.
#[derive(Clone, Copy)]
enum NodeSelection {
    /// Nodes that existed at the start of the run.
    Initial,
    /// Nodes that did not exist at the start (grown).
    New,
}

/// Times at which the node count first falls (discard) and first rises (growth).
pub fn node_events(t: &[f64], nodes: &[f64]) -> (Option<f64>, Option<f64>) {
    let mut discard = None;
    let mut grow = None;
    for k in 1..nodes.len().min(t.len()) {
        if discard.is_none() && nodes[k] < nodes[k - 1] {
            discard = Some(t[k]);
        }
        if grow.is_none() && nodes[k] > nodes[k - 1] {
            grow = Some(t[k]);
        }
    }
    (
        discard.filter(|v| v.is_finite()),
        grow.filter(|v| v.is_finite()),
    )
}

/// The node count at the last sample before `time`.
fn nodes_before(t: &[f64], nodes: &[f64], time: f64) -> f64 {
    let k = t
        .partition_point(|&x| x < time)
        .saturating_sub(1)
        .min(nodes.len().saturating_sub(1));
    nodes.get(k).copied().unwrap_or(f64::NAN)
}

/// One node's weight norm over a window.
struct NodeSeries {
    id: String,
    y: Vec<f64>,
    mean: f64,
}

/// A weight-convergence panel (Figs 22, 23, 25, 26): the norm of each selected node's
/// weight row over `range`, for the nodes that exist at both ends of it. The
/// [`HIGHLIGHTED`] nodes of largest mean norm are lines; the others a grey band from
/// their smallest to their largest norm at each sample.
fn weights_panel(
    table: &Table,
    range: (f64, f64),
    select: NodeSelection,
    what: &str,
) -> Result<Panel, String> {
    let t = table
        .col(columns::TIME)
        .ok_or("column `t` is not in the weights file")?;
    let rows: Vec<usize> = (0..t.len())
        .filter(|&k| t[k] >= range.0 && t[k] <= range.1)
        .collect();
    let (Some(&first), Some(&last)) = (rows.first(), rows.last()) else {
        return Err(format!(
            "no weight samples between {:.1} and {:.1} s",
            range.0, range.1
        ));
    };
    let x: Vec<f64> = rows.iter().map(|&k| t[k]).collect();
    let mut nodes = Vec::new();
    for name in table
        .columns
        .iter()
        .filter(|c| c.starts_with(columns::NODE_WEIGHT_PREFIX))
    {
        let Some(w) = table.col(name) else { continue };
        let initial = w.first().is_some_and(|v| v.is_finite());
        let wanted = match select {
            NodeSelection::Initial => initial,
            NodeSelection::New => !initial,
        };
        if !wanted || !w[first].is_finite() || !w[last].is_finite() {
            continue;
        }
        let y: Vec<f64> = rows.iter().map(|&k| w[k]).collect();
        let finite: Vec<f64> = y.iter().copied().filter(|v| v.is_finite()).collect();
        let mean = finite.iter().sum::<f64>() / finite.len().max(1) as f64;
        let id = name[columns::NODE_WEIGHT_PREFIX.len()..].to_string();
        nodes.push(NodeSeries { id, y, mean });
    }
    if nodes.is_empty() {
        return Err(format!(
            "no {what} exist from {:.1} to {:.1} s",
            range.0, range.1
        ));
    }
    let total = nodes.len();
    // Most active first; ties keep the file order.
    nodes.sort_by(|a, b| b.mean.total_cmp(&a.mean));
    let rest = nodes.split_off(HIGHLIGHTED.min(total));
    let mut p = panel(
        format!("{total} {what}, {:.0}-{:.0} s", range.0, range.1),
        "|W_i| (weight row norm)",
        Vec::new(),
    );
    if !rest.is_empty() {
        p.title = format!(
            "{total} {what}, {:.0}-{:.0} s: the {} of largest mean norm, and the other {}",
            range.0,
            range.1,
            nodes.len(),
            rest.len()
        );
        p.bands.push(spread(&x, &rest));
    }
    // No grey: the band is grey.
    const COLORS: [usize; HIGHLIGHTED] = [0, 1, 2, 3, 4, 6];
    for (n, color) in nodes.iter().zip(COLORS) {
        p.lines
            .push(line(format!("node {}", n.id), &x, &n.y, color, false));
    }
    p.x_range = Some(range);
    Ok(p)
}

/// The band from the smallest to the largest norm of `nodes` at each sample.
fn spread(x: &[f64], nodes: &[NodeSeries]) -> Band {
    let mut lo = vec![f64::INFINITY; x.len()];
    let mut hi = vec![f64::NEG_INFINITY; x.len()];
    for n in nodes {
        for (k, &v) in n.y.iter().enumerate() {
            if v.is_finite() {
                lo[k] = lo[k].min(v);
                hi[k] = hi[k].max(v);
            }
        }
    }
    for k in 0..x.len() {
        if lo[k] > hi[k] {
            (lo[k], hi[k]) = (f64::NAN, f64::NAN);
        }
    }
    Band {
        label: format!("the other {} nodes (min to max)", nodes.len()),
        x: x.to_vec(),
        lo,
        hi,
    }
}

fn approx_panel(v: &Variant, j: &str, range: (f64, f64), what: &str) -> Result<Panel, String> {
    let t = time(v)?;
    let nodes = super::common::col(v, columns::NODES_F)?;
    let n = nodes_before(t, nodes, range.1);
    let mut p = panel(
        format!(
            "joint {}, {what}: {:.0} nodes, {:.0}-{:.0} s",
            super::common::short(j),
            n,
            range.0,
            range.1
        ),
        "f (N m)",
        vec![
            line(
                "f = M alpha' + C alpha + G (true arm)",
                t,
                joint_col(v, columns::F_TRUE, j)?,
                1,
                false,
            ),
            line(
                "f_hat (network)",
                t,
                joint_col(v, columns::F_ESTIMATE, j)?,
                0,
                true,
            ),
        ],
    );
    p.x_range = Some(range);
    Ok(p)
}

/// The run's node events: the variant, discard time, growth time and end time.
struct Events<'a> {
    variant: &'a Variant,
    discard: f64,
    grow: Option<f64>,
    end: f64,
}

impl Events<'_> {
    fn grow(&self) -> Result<f64, String> {
        self.grow
            .ok_or_else(|| "`nodes.f` never rises: no nodes were grown in this run".into())
    }
}

fn events(folder: &RunFolder) -> Result<Events<'_>, String> {
    let v = folder
        .variant("dynamic")
        .or(folder.variants.first())
        .ok_or("the run has no variants")?;
    let t = time(v)?;
    let (discard, grow) = node_events(t, super::common::col(v, columns::NODES_F)?);
    let discard = discard.ok_or("`nodes.f` never falls: no nodes were discarded in this run")?;
    let end = super::common::last_window(t, 0.0).map_or(0.0, |w| w.1);
    Ok(Events {
        variant: v,
        discard,
        grow,
        end,
    })
}

fn weights_table<'a>(folder: &'a RunFolder, e: &Events<'_>) -> Result<&'a Table, String> {
    folder
        .node_weights
        .iter()
        .find(|(name, _)| *name == e.variant.name)
        .map(|(_, t)| t)
        .ok_or_else(|| {
            format!(
                "the run folder has no {} (per-node weight norms; written by runs with dynamic nodes)",
                files::node_weights(&e.variant.name)
            )
        })
}

fn fig21(folder: &RunFolder) -> Result<Figure, String> {
    let (j, s) = joint0(folder)?;
    let e = events(folder)?;
    let window = folder.approximation_window();
    let before_growth = e.grow.unwrap_or(e.end);
    Ok(compared(
        format!("Fig. 21: approximation of f on {s} before and after the discard"),
        vec![
            approx_panel(
                e.variant,
                j,
                (e.discard - window, e.discard),
                "all initial nodes",
            )?,
            approx_panel(
                e.variant,
                j,
                (before_growth - window, before_growth),
                "after the discard",
            )?,
        ],
    ))
}

fn fig24(folder: &RunFolder) -> Result<Figure, String> {
    let (j, s) = joint0(folder)?;
    let e = events(folder)?;
    e.grow()?;
    let window = folder.approximation_window();
    Ok(figure(
        format!("Fig. 24: approximation of f on {s} after growth"),
        vec![approx_panel(
            e.variant,
            j,
            (e.end - window, e.end),
            "after growth",
        )?],
    ))
}

/// The weight figures: 22 (initial nodes until the discard), 23 (kept nodes until
/// growth), 25 (kept nodes under growth), 26 (grown nodes, once they all exist).
fn weights_figure(folder: &RunFolder, number: u32) -> Result<Figure, String> {
    let e = events(folder)?;
    let table = weights_table(folder, &e)?;
    let (title, range, select, what) = match number {
        22 => (
            "Fig. 22: weights of the initial nodes until the discard",
            (0.0, e.discard - 1e-6), // the last sample before the discard
            NodeSelection::Initial,
            "initial nodes",
        ),
        23 => (
            "Fig. 23: weights of the nodes kept by the discard",
            (e.discard, e.grow.unwrap_or(e.end)),
            NodeSelection::Initial,
            "kept nodes",
        ),
        25 => (
            "Fig. 25: weights of the kept initial nodes while and after nodes grow",
            (e.grow()?, e.end),
            NodeSelection::Initial,
            "kept initial nodes",
        ),
        _ => {
            let grow = e.grow()?;
            // New nodes appear one by one from `grow` on: show them once they all exist.
            let w_t = table
                .col(columns::TIME)
                .ok_or("column `t` is not in the weights file")?;
            let all_added = table
                .columns
                .iter()
                .filter(|c| c.starts_with(columns::NODE_WEIGHT_PREFIX))
                .filter_map(|c| table.col(c))
                .filter(|w| !w.first().is_some_and(|v| v.is_finite()))
                .filter_map(|w| w.iter().position(|v| v.is_finite()).map(|k| w_t[k]))
                .filter(|v| v.is_finite())
                .fold(grow, f64::max);
            (
                "Fig. 26: weights of the grown nodes",
                (all_added, e.end),
                NodeSelection::New,
                "grown nodes",
            )
        }
    };
    Ok(figure(
        title,
        vec![weights_panel(table, range, select, what)?],
    ))
}

fn node_count(folder: &RunFolder) -> Result<Figure, String> {
    let e = events(folder)?;
    let v = e.variant;
    let mut p = panel(
        format!("variant {}", v.name),
        "nodes",
        vec![line(
            "nodes of the f network",
            time(v)?,
            super::common::col(v, columns::NODES_F)?,
            0,
            false,
        )],
    );
    p.vlines.push(Marker {
        at: e.discard,
        label: format!("discard at {:.1} s", e.discard),
    });
    if let Some(g) = e.grow {
        p.vlines.push(Marker {
            at: g,
            label: format!("growth from {g:.1} s"),
        });
    }
    Ok(figure("Node count of the f network", vec![p]))
}

/// Figs 21-26 and S1.
pub fn plan(folder: &RunFolder) -> Vec<Planned> {
    vec![
        planned(21, "approximation_discard", fig21(folder)),
        planned(22, "weights_initial", weights_figure(folder, 22)),
        planned(23, "weights_after_discard", weights_figure(folder, 23)),
        planned(24, "approximation_growth", fig24(folder)),
        planned(25, "weights_kept_after_growth", weights_figure(folder, 25)),
        planned(26, "weights_new_nodes", weights_figure(folder, 26)),
        extra(
            "S1",
            "s1_node_count",
            "Node count of the f network over the run (not in the paper).",
            columns::NODES_F,
            node_count(folder),
        ),
    ]
}
