//! Figs 7-26 of the paper: number, scenario, caption and the columns they are drawn from.

/// A figure of the paper: its number, the scenario that produces it and its caption.
#[derive(Clone, Copy, Debug)]
pub struct PaperFigure {
    /// Figure number in the paper.
    pub number: u32,
    /// The scenario (experiment) whose run folder holds its data.
    pub scenario: &'static str,
    /// The paper's caption.
    pub caption: &'static str,
    /// The data it shows, in terms of this project's outputs.
    pub data: &'static str,
}

/// Figs 7-26 of the paper and where their data lives.
pub const PAPER_FIGURES: &[PaperFigure] = &[
    PaperFigure { number: 7, scenario: "deadzone", caption: "The tracking performance of the end-effector.", data: "hand position from forward kinematics of q_d.* and q.* (nn_compensated), needs the URDF" },
    PaperFigure { number: 8, scenario: "deadzone", caption: "The tracking error of the end-effector.", data: "ee_error (nn_compensated, nn_uncompensated); y-axis sized to the evaluation window" },
    PaperFigure { number: 9, scenario: "deadzone", caption: "The tracking performance of joint s0 with NN compensation.", data: "q_d.s0, q.s0 (nn_compensated)" },
    PaperFigure { number: 10, scenario: "deadzone", caption: "The tracking performance of joint s0 without NN compensation.", data: "q_d.s0, q.s0 (nn_uncompensated)" },
    PaperFigure { number: 11, scenario: "deadzone", caption: "The tracking errors of joint s0 with/without NN compensation.", data: "q_r.s0 - q.s0 (nn_compensated, nn_uncompensated)" },
    PaperFigure { number: 12, scenario: "deadzone", caption: "The control inputs of joint s0.", data: "tau_cmd.s0, tau_applied.s0 and the deadzone band (nn_compensated, nn_uncompensated), one y range" },
    PaperFigure { number: 13, scenario: "free_motion", caption: "The free-motion training trajectory.", data: "q.* of a run of scenario free_motion" },
    PaperFigure { number: 14, scenario: "free_motion_validation", caption: "The validation trajectory.", data: "q.* of a run of scenario free_motion_validation (or of validation_VARIANT.csv when it carries them)" },
    PaperFigure { number: 15, scenario: "admittance", caption: "The validation performance with proposed observer.", data: "target.* and prediction.* of validation_VARIANT.csv (the paper's `learned` first)" },
    PaperFigure { number: 16, scenario: "admittance", caption: "The test trajectory.", data: "q.* of the run" },
    PaperFigure { number: 17, scenario: "admittance", caption: "The test performance with proposed observer.", data: "tau_ext.s0 and tau_ext_hat.s0, one panel per variant, one y range, contact window shaded" },
    PaperFigure { number: 18, scenario: "admittance", caption: "The trajectory adaptation of joint s0.", data: "q_d.s0 and q_r.s0 of every variant, contact window shaded" },
    PaperFigure { number: 19, scenario: "admittance", caption: "The trajectory tracking of joint s0.", data: "q_r.s0 and q.s0, one panel per variant, one y range, contact window shaded" },
    PaperFigure { number: 20, scenario: "admittance", caption: "The performance of trajectory constraint.", data: "q_r.s0 against the saturation bounds centre +- half_range of scenario.toml, contact window shaded" },
    PaperFigure { number: 21, scenario: "dynamic_nodes", caption: "The function approximation with 512 NN nodes and 304 NN nodes.", data: "f.s0, f_hat.s0 in the windows before discard and before growth (nodes.f finds them), one y range" },
    PaperFigure { number: 22, scenario: "dynamic_nodes", caption: "The convergence of NN weight with 512 NN nodes.", data: "w.ID of weights_VARIANT.csv: the most active nodes over a band of the rest" },
    PaperFigure { number: 23, scenario: "dynamic_nodes", caption: "The convergence of NN weight with 304 NN nodes.", data: "w.ID of weights_VARIANT.csv: the most active nodes over a band of the rest" },
    PaperFigure { number: 24, scenario: "dynamic_nodes", caption: "The function approximation with dynamic RBFNN learning framework.", data: "f.s0, f_hat.s0 in the last window, after growth" },
    PaperFigure { number: 25, scenario: "dynamic_nodes", caption: "The convergence of NN weight with 304 NN nodes under dynamic RBFNN learning framework.", data: "w.ID of weights_VARIANT.csv: the most active nodes over a band of the rest" },
    PaperFigure { number: 26, scenario: "dynamic_nodes", caption: "The convergence of NN weight of 100 new NN nodes.", data: "w.ID of weights_VARIANT.csv: the most active nodes over a band of the rest" },
];

/// The catalogue entry of Fig `number`.
pub fn paper(number: u32) -> &'static PaperFigure {
    PAPER_FIGURES
        .iter()
        .find(|f| f.number == number)
        .unwrap_or(&PAPER_FIGURES[0])
}
