use super::dynamic_nodes::node_events;
use super::*;
use crate::folder::Variant;
use crate::table::Table;

const J: [&str; 2] = ["left_s0", "left_s1"];

const ALL: [&str; 9] = [
    "q_d",
    "q_r",
    "q",
    "qdot",
    "q_meas",
    "tau_cmd",
    "tau_applied",
    "tau_ext",
    "tau_ext_hat",
];

fn table(prefixes: &[&str], extra: &[&str], rows: usize) -> Table {
    let mut names = vec!["t".to_string()];
    for p in prefixes {
        for j in J {
            names.push(format!("{p}.{j}"));
        }
    }
    names.extend(extra.iter().map(|s| s.to_string()));
    let data = (0..names.len())
        .map(|c| {
            (0..rows)
                .map(|k| {
                    if c == 0 {
                        k as f64 * 0.1
                    } else {
                        (k as f64 * 0.3 + c as f64).sin()
                    }
                })
                .collect()
        })
        .collect();
    Table::from_columns(names, data)
}

/// A deadzone comparison: the neural controller with and without compensation and PD on
/// the paper's deadzone, and a wide pair (`wide_on`, `wide_off`).
const TOML: &str = "evaluation_start = 1.5\n\
    [controller]\nkind = \"neural\"\n\
    [[plant.deadzones]]\njoint = \"left_s0\"\nd_left = -0.49\nd_right = 0.49\n\
    [variants.nn_uncompensated]\ncontroller.neural.deadzone_compensation = false\n\
    [variants.pd]\ncontroller.kind = \"pd\"\n\
    [variants.wide_on]\nplant.deadzones = [{ joint = \"left_s0\", d_left = -5.0, d_right = 5.0 }]\n\
    [variants.wide_off]\ncontroller.neural.deadzone_compensation = false\n\
    plant.deadzones = [{ joint = \"left_s0\", d_left = -5.0, d_right = 5.0 }]\n";

/// An observer comparison: a joint-space admittance driven by each variant's observer.
const OBSERVERS: &str = "[admittance]\ndamping = 3\nstiffness = 5\n\
    [admittance.saturation]\nrho = 0.95\nhalf_range = [1.1, inf]\n\
    [observer]\nkind = \"oracle\"\n\
    [variants.learned]\nobserver.kind = \"learned\"\n\
    [variants.momentum]\nobserver.kind = \"momentum\"\n";

/// A free-motion data run.
const DATA: &str = "[record]\nfree_motion_csv = true\n";

fn folder_with(scenario: &str, variants: &[(&str, Table)], toml: &str) -> RunFolder {
    RunFolder {
        dir: ".".into(),
        scenario: scenario.into(),
        plant: None,
        joints: J.iter().map(|s| s.to_string()).collect(),
        variants: variants
            .iter()
            .map(|(n, t)| Variant {
                name: n.to_string(),
                metrics: Default::default(),
                table: t.clone(),
            })
            .collect(),
        warnings: Vec::new(),
        health: None,
        scenario_toml: Some(toml.parse().unwrap()),
        settings: None,
        free_motion: Vec::new(),
        node_weights: Vec::new(),
        observer_validation: Vec::new(),
    }
}

fn folder(scenario: &str, variants: &[(&str, Table)]) -> RunFolder {
    folder_with(scenario, variants, TOML)
}

fn figure_of<'a>(plan: &'a [Planned], id: &str) -> &'a Figure {
    plan.iter()
        .find(|p| p.id == id)
        .unwrap_or_else(|| panic!("Fig {id} not planned"))
        .figure
        .as_ref()
        .unwrap_or_else(|e| panic!("Fig {id}: {e}"))
}

#[test]
fn catalogue_covers_figs_7_to_26_once() {
    let numbers: Vec<u32> = PAPER_FIGURES.iter().map(|f| f.number).collect();
    assert_eq!(numbers, (7..=26).collect::<Vec<_>>());
    for f in PAPER_FIGURES {
        let expected = match f.number {
            7..=12 => "deadzone",
            13 => "free_motion",
            14 => "free_motion_validation",
            15..=20 => "admittance",
            _ => "dynamic_nodes",
        };
        assert_eq!(f.scenario, expected, "Fig {}", f.number);
    }
}

#[test]
fn experiment_a_maps_figures_to_columns() {
    let t = table(&ALL, &["ee_error"], 100);
    let f = folder(
        "deadzone",
        &[("nn_compensated", t.clone()), ("nn_uncompensated", t)],
    );
    let plan = plan(&f, Err("no URDF in this test".into()));
    let ids: Vec<&str> = plan.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids, ["7", "8", "9", "10", "11", "12"]);
    assert_eq!(plan[0].figure.as_ref().unwrap_err(), "no URDF in this test");
    // Fig 11: the error line is q_r - q of s0, computed row by row.
    let fig11 = figure_of(&plan, "11");
    let v = f.variant("nn_compensated").unwrap();
    let expected: Vec<f64> = v
        .table
        .col("q_r.left_s0")
        .unwrap()
        .iter()
        .zip(v.table.col("q.left_s0").unwrap())
        .map(|(a, b)| a - b)
        .collect();
    let compensated = fig11.panels[0]
        .lines
        .iter()
        .find(|l| l.label.contains("nn_compensated"))
        .unwrap();
    assert_eq!(compensated.y, expected);
    // Fig 12 carries the deadzone band from scenario.toml and the last 6 s, and its two
    // panels share one y range.
    let fig12 = figure_of(&plan, "12");
    assert!(fig12.shared_y);
    let band: Vec<f64> = fig12.panels[0].hlines.iter().map(|m| m.at).collect();
    assert_eq!(band, [-0.49, 0.49]);
    let band: Vec<f64> = fig12.panels[1].hlines.iter().map(|m| m.at).collect();
    assert_eq!(band, [-0.49, 0.49]);
    let r = fig12.panels[0].x_range.unwrap();
    let t_end = *v.table.col("t").unwrap().last().unwrap();
    assert!(
        (r.1 - t_end).abs() < 1e-12 && (r.1 - r.0 - 6.0).abs() < 1e-9,
        "{r:?}"
    );
    // Fig 8's y axis is sized to the evaluation window.
    assert_eq!(figure_of(&plan, "8").panels[0].y_fit_from, Some(1.5));
}

#[test]
fn missing_column_makes_a_figure_unavailable_with_the_column_named() {
    let full = table(&ALL, &["ee_error"], 20);
    let keep: Vec<usize> = (0..full.columns.len())
        .filter(|&k| full.columns[k] != "tau_applied.left_s0")
        .collect();
    let partial = Table::from_columns(
        keep.iter().map(|&k| full.columns[k].clone()).collect(),
        keep.iter().map(|&k| full.data[k].clone()).collect(),
    );
    let f = folder(
        "deadzone",
        &[("nn_compensated", partial), ("nn_uncompensated", full)],
    );
    let plan = plan(&f, Err("no URDF".into()));
    let fig12 = plan.iter().find(|p| p.id == "12").unwrap();
    let reason = fig12.figure.as_ref().unwrap_err();
    assert!(
        reason.contains("tau_applied.left_s0") && reason.contains("nn_compensated.csv"),
        "{reason}"
    );
    // The other figures are unaffected.
    assert!(plan.iter().find(|p| p.id == "11").unwrap().figure.is_ok());
}

#[test]
fn missing_variant_is_named() {
    let f = folder("deadzone", &[("pd", table(&ALL, &["ee_error"], 10))]);
    let plan = plan(&f, Err("no URDF".into()));
    let reason = plan
        .iter()
        .find(|p| p.id == "9")
        .unwrap()
        .figure
        .as_ref()
        .unwrap_err()
        .clone();
    assert!(
        reason.contains("no variant with the neural controller with deadzone compensation"),
        "{reason}"
    );
}

/// A dynamic-nodes run over 0..100 s: 512 nodes, 300 after 40 s, then +1 a second from
/// 60 s to 310.
fn dynamic_folder() -> (RunFolder, Vec<f64>) {
    let t: Vec<f64> = (0..100).map(|k| k as f64).collect();
    let nodes: Vec<f64> = t
        .iter()
        .map(|&x| {
            if x < 40.0 {
                512.0
            } else if x < 60.0 {
                300.0
            } else {
                300.0 + (x - 59.0).min(10.0)
            }
        })
        .collect();
    assert_eq!(node_events(&t, &nodes), (Some(40.0), Some(60.0)));
    let f_col: Vec<f64> = t.iter().map(|x| x.sin()).collect();
    let tab = Table::from_columns(
        vec![
            "t".into(),
            "f.left_s0".into(),
            "f_hat.left_s0".into(),
            "nodes.f".into(),
        ],
        vec![t.clone(), f_col.clone(), f_col, nodes],
    );
    (
        folder_with(
            "renamed",
            &[("dynamic", tab)],
            "[dynamic_nodes]\napproximation_window = 12.0\n",
        ),
        t,
    )
}

/// A weights table: `alive(id, t)` says when node `id` exists (its norm is `0.1 (id + 1) t`).
fn weights(t: &[f64], ids: usize, alive: &dyn Fn(usize, f64) -> bool) -> Table {
    let mut names = vec!["t".to_string()];
    let mut cols = vec![t.to_vec()];
    for id in 0..ids {
        names.push(format!("w.{id}"));
        cols.push(
            t.iter()
                .map(|&x| {
                    if alive(id, x) {
                        0.1 * (id + 1) as f64 * x
                    } else {
                        f64::NAN
                    }
                })
                .collect(),
        );
    }
    Table::from_columns(names, cols)
}

#[test]
fn experiment_c_finds_discard_and_growth_from_node_counts() {
    let (f, t) = dynamic_folder();
    let plan = plan(&f, Err("unused".into()));
    let fig21 = figure_of(&plan, "21");
    assert!(fig21.shared_y, "the two windows are compared");
    assert_eq!(fig21.panels[0].x_range, Some((28.0, 40.0)));
    assert_eq!(fig21.panels[1].x_range, Some((48.0, 60.0)));
    assert!(
        fig21.panels[0].title.contains("512 nodes"),
        "{}",
        fig21.panels[0].title
    );
    assert!(
        fig21.panels[1].title.contains("300 nodes"),
        "{}",
        fig21.panels[1].title
    );
    let fig24 = figure_of(&plan, "24");
    assert!(
        fig24.panels[0].title.contains("310 nodes"),
        "{}",
        fig24.panels[0].title
    );
    for n in ["22", "23", "25", "26"] {
        let reason = plan
            .iter()
            .find(|p| p.id == n)
            .unwrap()
            .figure
            .as_ref()
            .unwrap_err();
        assert!(reason.contains("weights_dynamic.csv"), "{reason}");
    }

    // With per-node weights: 4 initial nodes, 2 of them discarded at 40 s, 3 grown at
    // 60, 61 and 62 s.
    let mut f = f;
    let starts = [60.0, 61.0, 62.0];
    f.node_weights = vec![(
        "dynamic".into(),
        weights(&t, 7, &|id, x| match id {
            0 | 1 => true,
            2 | 3 => x < 40.0,
            _ => x >= starts[id - 4],
        }),
    )];
    let with_weights = super::plan(&f, Err("unused".into()));
    let lines = |id: &str| figure_of(&with_weights, id).panels[0].lines.len();
    assert_eq!(lines("22"), 4, "all initial nodes until the discard");
    assert_eq!(lines("23"), 2, "the kept nodes");
    assert_eq!(lines("25"), 2, "the kept nodes after growth");
    assert_eq!(lines("26"), 3, "the grown nodes");
    assert_eq!(
        figure_of(&with_weights, "26").panels[0].x_range,
        Some((62.0, 99.0))
    );
    assert!(
        figure_of(&with_weights, "22").panels[0].bands.is_empty(),
        "few nodes: no band"
    );
}

#[test]
fn weight_figures_highlight_the_most_active_nodes_over_a_band_of_the_rest() {
    let (mut f, t) = dynamic_folder();
    // 40 initial nodes, all alive: node id has norm 0.1 (id + 1) t.
    f.node_weights = vec![("dynamic".into(), weights(&t, 40, &|_, _| true))];
    let plan = plan(&f, Err("unused".into()));
    let p = &figure_of(&plan, "22").panels[0];
    let labels: Vec<&str> = p.lines.iter().map(|l| l.label.as_str()).collect();
    assert_eq!(
        labels,
        ["node 39", "node 38", "node 37", "node 36", "node 35", "node 34"],
        "the largest mean norms, largest first"
    );
    assert_eq!(p.bands.len(), 1);
    let band = &p.bands[0];
    assert!(band.label.contains("34"), "{}", band.label);
    // The band spans nodes 0..=33: from 0.1 t to 3.4 t.
    let k = band.x.iter().position(|&x| x == 10.0).unwrap();
    assert!((band.lo[k] - 1.0).abs() < 1e-12 && (band.hi[k] - 34.0).abs() < 1e-9);
    assert!(p.title.contains("40 initial nodes"), "{}", p.title);
}

#[test]
fn experiment_b_draws_fig_13_and_14_each_from_its_own_data() {
    let t = table(&ALL, &[], 30);
    let training = plan(
        &folder_with("free_motion", &[("base", t.clone())], DATA),
        Err("unused".into()),
    );
    let ids: Vec<(&str, bool)> = training
        .iter()
        .map(|p| (p.id.as_str(), p.figure.is_ok()))
        .collect();
    assert_eq!(ids, [("13", true), ("14", false), ("15", false)]);
    // A validation run's data are the validation trajectory, never Fig 13's.
    let mut validation_folder = folder_with("free_motion_validation", &[("base", t.clone())], DATA);
    let other = table(&["q"], &[], 12);
    validation_folder.free_motion = vec![("free_motion.csv".into(), other.clone())];
    let validation = plan(&validation_folder, Err("unused".into()));
    assert!(validation[0]
        .figure
        .as_ref()
        .unwrap_err()
        .contains("scenarios/free_motion.toml"));
    let fig14 = figure_of(&validation, "14");
    assert_eq!(fig14.panels[0].lines.len(), J.len());
    assert_eq!(fig14.panels[0].lines[1].y, other.col("q.left_s1").unwrap());
    assert!(fig14.panels[0].title.contains("free_motion.csv"));

    let admittance = plan(
        &folder_with(
            "renamed",
            &[("momentum", t.clone()), ("learned", t)],
            OBSERVERS,
        ),
        Err("unused".into()),
    );
    let ids: Vec<&str> = admittance.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids, ["13", "14", "15", "16", "17", "18", "19", "20"]);
    assert!(admittance[0].figure.is_err() && admittance[1].figure.is_err());
    assert!(admittance[2].figure.is_err(), "no validation file yet");
    // Figs 17 and 19 compare the variants on one y range; Fig 16 shows the learned one.
    assert!(figure_of(&admittance, "17").shared_y && figure_of(&admittance, "19").shared_y);
    assert!(figure_of(&admittance, "16").panels[0]
        .title
        .contains("learned"));
}

#[test]
fn experiment_b_validation_file_gives_figs_14_and_15() {
    let mut with_validation =
        folder_with("admittance", &[("learned", table(&[], &[], 5))], OBSERVERS);
    let columns: Vec<String> = std::iter::once("t".to_string())
        .chain(J.iter().map(|j| format!("target.{j}")))
        .chain(J.iter().map(|j| format!("prediction.{j}")))
        .chain(J.iter().map(|j| format!("q.{j}")))
        .collect();
    let data = (0..columns.len())
        .map(|c| (0..10).map(|k| (k * c) as f64).collect())
        .collect();
    with_validation.observer_validation =
        vec![("learned".into(), Table::from_columns(columns, data))];
    let plan = super::plan(&with_validation, Err("unused".into()));
    let panels = &figure_of(&plan, "15").panels;
    assert_eq!(panels.len(), J.len());
    assert_eq!(panels[1].lines.len(), 2);
    // The validation file carries the angles: Fig 14 is drawn from them.
    let fig14 = figure_of(&plan, "14");
    assert!(fig14.panels[0].title.contains("validation_learned.csv"));
    assert_eq!(fig14.panels[0].lines[0].y[3], 3.0 * 5.0);
}

#[test]
fn contact_windows_are_shaded_from_the_scenario_or_the_data() {
    let toml = format!(
        "{OBSERVERS}[[plant.environment.joint_springs]]\njoints = [\"left_s0\"]\nt_start = 1.0\nt_end = 2.0\n"
    );
    let t = table(&ALL, &[], 40);
    let f = folder_with("admittance", &[("learned", t.clone())], &toml);
    let plan = plan(&f, Err("unused".into()));
    for id in ["16", "17", "18", "19", "20"] {
        let spans = &figure_of(&plan, id).panels[0].spans;
        assert_eq!(spans.len(), 1, "Fig {id}");
        assert_eq!((spans[0].from, spans[0].to), (1.0, 2.0), "Fig {id}");
        assert!(spans[0].label.contains("environment acts"));
    }
    // Without an environment in scenario.toml: where the true external torque is non-zero.
    let mut quiet = t.clone();
    let k = quiet
        .columns
        .iter()
        .position(|c| c == "tau_ext.left_s0")
        .unwrap();
    let j = quiet
        .columns
        .iter()
        .position(|c| c == "tau_ext.left_s1")
        .unwrap();
    for (row, v) in quiet.data[k].iter_mut().enumerate() {
        *v = if (10..20).contains(&row) { 0.5 } else { 0.0 };
    }
    quiet.data[j].iter_mut().for_each(|v| *v = 0.0);
    let f = folder_with("admittance", &[("learned", quiet)], OBSERVERS);
    let plan = super::plan(&f, Err("unused".into()));
    let spans = &figure_of(&plan, "17").panels[0].spans;
    assert_eq!(spans.len(), 1);
    assert!((spans[0].from - 1.0).abs() < 1e-12 && (spans[0].to - 1.9).abs() < 1e-12);
}

#[test]
fn a_mujoco_run_gets_the_experiment_b_figures() {
    let mut f = folder("baxter_mujoco", &[("learned", table(&ALL, &[], 20))]);
    f.plant = Some("mujoco".into());
    let ids: Vec<String> = plan(&f, Err("unused".into()))
        .into_iter()
        .map(|p| p.id)
        .collect();
    assert_eq!(ids, ["13", "14", "15", "16", "17", "18", "19", "20"]);
}

fn hand_table(rows: usize) -> Table {
    let mut t = table(&ALL, &[], rows);
    for prefix in ["f_hand", "f_hand_hat", "x_hand", "x_hand_r", "x_hand_d"] {
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            t.columns.push(format!("{prefix}.{axis}"));
            t.data.push(
                (0..rows)
                    .map(|k| match prefix {
                        "f_hand" if a == 0 && (5..10).contains(&k) => -20.0,
                        "f_hand" => 0.0,
                        "f_hand_hat" => 0.1 * k as f64,
                        _ => 0.5 + 0.01 * k as f64 + a as f64,
                    })
                    .collect(),
            );
        }
    }
    t
}

#[test]
fn task_space_runs_get_the_hand_contact_figures() {
    let toml = "[[plant.environment.walls]]\npoint = [0.6, 0.0, 0.0]\nnormal = [-1.0, 0.0, 0.0]\n";
    let t = hand_table(20);
    let f = folder_with(
        "hand_contact",
        &[("learned", t.clone()), ("oracle", t)],
        toml,
    );
    let plan = plan(&f, Err("unused".into()));
    let ids: Vec<&str> = plan.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids, ["H1", "H2", "H3"]);
    let h1 = figure_of(&plan, "H1");
    assert!(h1.shared_y);
    assert_eq!(h1.panels.len(), 2, "one panel per variant");
    assert_eq!(h1.panels[0].lines.len(), 6, "true and estimate per axis");
    assert!(h1.panels[0].lines[0].dashed && !h1.panels[0].lines[1].dashed);
    let spans = &h1.panels[0].spans;
    assert_eq!(spans.len(), 1);
    assert!((spans[0].from - 0.5).abs() < 1e-12 && (spans[0].to - 0.9).abs() < 1e-12);
    // H2: signed distance from the wall x = 0.6, free space towards -x: 0.6 - x.
    let h2 = figure_of(&plan, "H2");
    let actual = h2.panels[0]
        .lines
        .iter()
        .find(|l| l.label == "actual hand")
        .unwrap();
    assert!(
        (actual.y[3] - (0.6 - 0.53)).abs() < 1e-12,
        "{}",
        actual.y[3]
    );
    assert_eq!(h2.panels[0].hlines[0].at, 0.0);
    // H3: q_r - q_d, only the joints whose q_r departs from q_d (all of them here).
    let h3 = figure_of(&plan, "H3");
    assert_eq!(h3.panels.len(), J.len());
    let v = f.variant("learned").unwrap();
    let (r, d) = (
        v.table.col("q_r.left_s1").unwrap(),
        v.table.col("q_d.left_s1").unwrap(),
    );
    assert_eq!(h3.panels[1].lines[0].y[4], r[4] - d[4]);
    // Without a wall: H2 says why.
    let f = folder_with("hand_contact", &[("learned", hand_table(20))], "");
    let plan = super::plan(&f, Err("unused".into()));
    let reason = plan[1].figure.as_ref().unwrap_err();
    assert!(reason.contains("walls"), "{reason}");
}

/// Columns of every per-joint signal where `tracking(joint)` sets how far `q` is from `q_r`.
fn tracking_table(rows: usize, error: &dyn Fn(&str) -> f64) -> Table {
    let mut t = table(&ALL, &["ee_error"], rows);
    for j in J {
        let r = t
            .columns
            .iter()
            .position(|c| *c == format!("q_r.{j}"))
            .unwrap();
        let q = t
            .columns
            .iter()
            .position(|c| *c == format!("q.{j}"))
            .unwrap();
        let e = error(j);
        t.data[q] = t.data[r].iter().map(|x| x - e).collect();
    }
    t
}

#[test]
fn a_renamed_deadzone_scenario_gets_the_deadzone_report_for_its_deadzone_joint() {
    // The Panda's file, renamed, with variants named otherwise and the deadzone on the
    // second joint: the report is found from the deadzone and the controllers, and its
    // figures show that joint.
    let toml = "evaluation_start = 0.5\n\
        [controller]\nkind = \"neural\"\n\
        [[plant.deadzones]]\njoint = \"left_s1\"\nd_left = -0.3\nd_right = 0.4\n\
        [variants.off]\ncontroller.neural.deadzone_compensation = false\n\
        [variants.linear]\ncontroller.kind = \"pd\"\n";
    let t = tracking_table(30, &|_| 0.01);
    let mut f = folder_with(
        "my_arm_experiment",
        &[("linear", t.clone()), ("on", t.clone()), ("off", t)],
        toml,
    );
    for (name, rmse) in [
        ("on", [0.001, 0.002]),
        ("off", [0.001, 0.02]),
        ("linear", [0.003, 0.03]),
    ] {
        let v = f.variants.iter_mut().find(|v| v.name == name).unwrap();
        v.metrics
            .insert("tracking_rmse".into(), serde_json::json!(rmse));
    }
    assert_eq!(
        crate::experiment::Experiment::of(&f),
        crate::experiment::Experiment::Deadzone
    );
    let groups = crate::experiment::deadzone_groups(&f);
    assert_eq!(groups.len(), 1);
    assert_eq!(
        (
            groups[0].with.as_deref(),
            groups[0].without.as_deref(),
            groups[0].pd.as_deref()
        ),
        (Some("on"), Some("off"), Some("linear"))
    );
    let plan = plan(&f, Err("no URDF".into()));
    let ids: Vec<&str> = plan.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids, ["7", "8", "9", "10", "11", "12"]);
    let fig12 = figure_of(&plan, "12");
    assert!(fig12.title.contains("joint s1"), "{}", fig12.title);
    let band: Vec<f64> = fig12.panels[0].hlines.iter().map(|m| m.at).collect();
    assert_eq!(band, [-0.3, 0.4]);
    let fig11 = figure_of(&plan, "11");
    assert!(fig11.panels[0]
        .lines
        .iter()
        .all(|l| l.y.iter().all(|e| (e - 0.01).abs() < 1e-12)));
    let fig9 = plan.iter().find(|p| p.id == "9").unwrap();
    assert!(fig9.caption.contains("joint s1"), "{}", fig9.caption);
    assert!(figure_of(&plan, "9").panels[0].title.contains("variant on"));
}

#[test]
fn the_wide_deadzone_pair_gets_figs_11b_and_12b_with_its_own_band() {
    let t = table(&ALL, &["ee_error"], 100);
    let f = folder(
        "renamed",
        &[
            ("nn_compensated", t.clone()),
            ("nn_uncompensated", t.clone()),
            ("pd", t.clone()),
            ("wide_on", t.clone()),
            ("wide_off", t),
        ],
    );
    let plan = plan(&f, Err("no URDF".into()));
    let ids: Vec<&str> = plan.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids, ["7", "8", "9", "10", "11", "12", "11b", "12b"]);
    let fig12b = figure_of(&plan, "12b");
    for p in &fig12b.panels {
        let band: Vec<f64> = p.hlines.iter().map(|m| m.at).collect();
        assert_eq!(band, [-5.0, 5.0], "{}", p.title);
    }
    assert!(
        fig12b.panels[0].title.contains("wide_on") && fig12b.panels[1].title.contains("wide_off")
    );
}

#[test]
fn an_unknown_scenario_shows_its_worst_joint_and_every_joint() {
    let t = tracking_table(30, &|j| if j == "left_s1" { 0.2 } else { 0.01 });
    let mut f = folder_with("mine", &[("a", t)], "");
    f.variants[0]
        .metrics
        .insert("tracking_rmse".into(), serde_json::json!([0.01, 0.2]));
    let plan = plan(&f, Err("unused".into()));
    let ids: Vec<&str> = plan.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids, ["S1", "S2", "S3"]);
    assert!(figure_of(&plan, "S1").title.contains("joint s1"));
    assert_eq!(figure_of(&plan, "S3").panels[0].lines.len(), J.len());
}

#[test]
fn an_observer_comparison_shows_the_joint_in_contact() {
    let toml = format!(
        "{OBSERVERS}[[plant.environment.joint_springs]]\njoints = [\"left_s1\"]\nt_start = 1.0\nt_end = 2.0\n"
    );
    let t = table(&ALL, &[], 40);
    let f = folder_with("renamed", &[("learned", t.clone()), ("momentum", t)], &toml);
    assert_eq!(
        crate::experiment::Experiment::of(&f),
        crate::experiment::Experiment::Admittance { mujoco: false }
    );
    let plan = plan(&f, Err("unused".into()));
    for id in ["17", "18", "19", "20"] {
        assert!(figure_of(&plan, id).title.contains("s1"), "Fig {id}");
    }
    // Fig 20's bound is that joint's: half_range inf on s1, so none is drawn.
    assert!(figure_of(&plan, "20").panels[0].hlines.is_empty());
}
