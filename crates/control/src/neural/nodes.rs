//! The controller's networks by identifier and the dynamic-node requests of docs/method.md
//! section 4 (the events themselves are in `growth.rs`).

use admittance_learning::rbf::GrowthParams;
use serde::{Deserialize, Serialize};

/// The networks of a neural controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NetworkId {
    /// The lumped f network.
    F,
    /// Split form: inertia network.
    M,
    /// Split form: Coriolis network.
    C,
    /// Split form: gravity network.
    G,
    /// The deadzone compensation network.
    Deadzone,
}

impl NetworkId {
    /// All identifiers, in a fixed order.
    pub const ALL: [NetworkId; 5] = [
        NetworkId::F,
        NetworkId::M,
        NetworkId::C,
        NetworkId::G,
        NetworkId::Deadzone,
    ];

    /// `"f"`, `"m"`, `"c"`, `"g"`, `"deadzone"`.
    pub fn as_str(&self) -> &'static str {
        match self {
            NetworkId::F => "f",
            NetworkId::M => "m",
            NetworkId::C => "c",
            NetworkId::G => "g",
            NetworkId::Deadzone => "deadzone",
        }
    }

    pub(super) fn index(self) -> usize {
        self as usize
    }
}

/// A request to grow nodes near the trajectory (docs/method.md section 4, "Grow").
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrowthRequest {
    /// How many nodes to add in total.
    pub nodes: usize,
    /// Minimum number of control steps between two additions (spreads the new nodes along
    /// the trajectory); 1 = try every step.
    pub interval_steps: usize,
    /// Growth test (`m`, `Xi`, minimum spacing, placement on the segment). At each attempt a
    /// node is added at the network's current input iff the mean distance of its `m`
    /// nearest centres exceeds `Xi` and the spacing allows it (the RBF layer's
    /// `maybe_grow_at_last_input`).
    pub params: GrowthParams,
}

/// Progress of a growth request.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GrowthProgress {
    /// Nodes still to add.
    pub pending: usize,
    /// Nodes added since construction or reset.
    pub added: usize,
    /// Attempts that found the input already covered or too close to a centre.
    pub declined: usize,
}

#[derive(Clone, Copy, Debug, Default)]
pub(super) struct GrowthState {
    pub(super) request: Option<GrowthRequest>,
    pub(super) since: usize,
    pub(super) progress: GrowthProgress,
}
