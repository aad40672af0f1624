//! SNGNN-v2, the learned social-compliance reward (docs/spec.md 6.3 and 7): weight loading,
//! graph building and batched inference.
//!
//! - [`frame`]: the input frame of the current step (docs/spec.md 7.2); [`frame::record`] pushes it
//!   into the environment's history (call it on every non-terminal step, after the motion).
//! - [`history`]: the per-environment frame history in the state's columns and the choice of a
//!   graph's frames (docs/spec.md 7.4).
//! - [`graph`]: [`graph::build`] turns the chosen frames into the [`Graph`] the network sees
//!   (docs/spec.md 7.3), node for node and edge for edge as 0.1.1.
//! - [`model`]: the network and its reference forward pass; [`pieces`]: its edge weights as
//!   exact piecewise-linear tables, the fast pass; [`Scorer`]: both, shared per process.
//! - On a device, the tables' pass over a batch of [`packed`] graphs is the GPU backend's
//!   (`backend::gpu::sngnn_net`): this module is domain code, and GPU code depends on it.
//! - Weights: [`Weights::load`] reads the PyTorch file without torch; [`weights_path`] finds it.
//!
//! The weights are GPL-3.0 and never part of this repository: `socnav sngnn install` fetches
//! them from the socnavgym 0.1.1 wheel into a cache directory, and the config
//! (`reward.sngnn_weights`, overridden by `SOCNAV_SNGNN_WEIGHTS`) points to the file.

mod cache;
pub mod frame;
pub mod graph;
pub mod history;
pub mod model;
pub mod packed;
mod pickle;
pub mod pieces;
mod scorer;
mod weights;

use std::collections::BTreeMap;

pub use cache::{
    CACHE_ENV, CACHE_FILE, WEIGHTS_ENV, WeightsPath, WeightsSource, cache_dir, cached_weights,
    install_from_wheel, install_hint, load_weights, weights_path,
};
pub use scorer::{Scorer, SngnnReward, table_range};
pub use weights::{LAYERS, Layer, PARAMETERS, WHEEL_ENTRY, expected_tensors};

/// One float32 tensor of the model's state dict, row-major (PyTorch's `Linear` weight is
/// `(out, in)`).
#[derive(Debug, Clone, PartialEq)]
pub struct Tensor {
    /// Extent of each dimension.
    pub shape: Vec<usize>,
    /// The values, row-major, `shape.iter().product()` of them.
    pub data: Vec<f32>,
}

/// The model's 42 named tensors (docs/spec.md 7.1), names as in the PyTorch state dict
/// (`gnn_object.layers.0.edge_func.2.weight`, ...).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Weights {
    /// Tensors by state-dict name.
    pub tensors: BTreeMap<String, Tensor>,
}

impl Weights {
    /// The tensor called `name`; the names are checked when the weights are loaded, so a
    /// missing one here is a bug.
    #[expect(
        clippy::panic,
        reason = "tensor names are checked when the weights load"
    )]
    pub fn get(&self, name: &str) -> &Tensor {
        self.tensors
            .get(name)
            .unwrap_or_else(|| panic!("SNGNN weights lack {name:?} (checked at load time)"))
    }
}

/// Features per node (docs/spec.md 7.3).
pub const NODE_FEATURES: usize = 42;
/// Features per edge: the one-hot of the spatial relation (0-13) or the temporal one (14-17),
/// and the distance at index 17 (docs/spec.md 7.3-7.4).
pub const EDGE_FEATURES: usize = 18;
/// Relations, spatial and temporal.
pub const RELATIONS: usize = 18;
/// The relation whose one-hot is overwritten by its zero distance: its edge feature is all zero
/// (docs/spec.md 7.4's quirk, reproduced because it defines the model's input).
pub const ZERO_FEATURE_RELATION: u8 = 17;
const _: () = assert!(rel::TEMPORAL + 3 == ZERO_FEATURE_RELATION && RELATIONS == 18);

/// Relation indices (the one-hot position in the edge feature): 0.1.1's sorted spatial
/// relations, then the temporal ones.
pub mod rel {
    /// Goal → room.
    pub const G_R: u8 = 0;
    /// Object → person (a laptop to its user).
    pub const O_P: u8 = 1;
    /// Object → room.
    pub const O_R: u8 = 2;
    /// Person → object.
    pub const P_O: u8 = 3;
    /// Person → person (group members).
    pub const P_P: u8 = 4;
    /// Person → room.
    pub const P_R: u8 = 5;
    /// Person → wall segment.
    pub const P_W: u8 = 6;
    /// Room → goal.
    pub const R_G: u8 = 7;
    /// Room → object.
    pub const R_O: u8 = 8;
    /// Room → person.
    pub const R_P: u8 = 9;
    /// Room → wall segment.
    pub const R_W: u8 = 10;
    /// Self-loop.
    pub const SELF: u8 = 11;
    /// Wall segment → person.
    pub const W_P: u8 = 12;
    /// Wall segment → room.
    pub const W_R: u8 = 13;
    /// Frame k − 1 → frame k is `TEMPORAL + 2 (k − 1)`, the reverse one more.
    pub const TEMPORAL: u8 = 14;
}

/// Node feature indices (docs/spec.md 7.3's table, 0.1.1's `get_features` order).
pub mod feature {
    /// Node type one-hot: human.
    pub const HUMAN: usize = 0;
    /// Object.
    pub const OBJECT: usize = 1;
    /// Room.
    pub const ROOM: usize = 2;
    /// Wall segment.
    pub const WALL: usize = 3;
    /// Goal.
    pub const GOAL: usize = 4;
    /// `is_t_0`; frame k sets `IS_T + k`.
    pub const IS_T: usize = 5;
    /// Person: x, y (/10), angular, x and y velocity (/10), sin and cos of the angle, ρ, 1 − ρ.
    pub const PERSON: usize = 8;
    /// Room: advance command / 3.5, rotation command / 4.
    pub const ROBOT: usize = 17;
    /// Object: the person's nine, then size x, size y (m) before ρ and 1 − ρ.
    pub const OBJECT_BASE: usize = 19;
    /// Room: humans / 15, humans² / 225.
    pub const ROOM_HUMANS: usize = 30;
    /// Wall segment: x, y (/10), sin and cos of its direction, ρ, 1 − ρ.
    pub const WALL_BASE: usize = 32;
    /// Goal: x, y (/10), ρ, 1 − ρ.
    pub const GOAL_BASE: usize = 38;
}

/// The graph the network sees for one environment and step: up to three frames stacked
/// (docs/spec.md 7.3-7.4). An edge's feature is a function of its relation and distance only
/// ([`Graph::edge_feature`]), so edges carry those two instead of 18 floats.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Graph {
    /// Number of nodes; node 0 is the room node of the newest frame.
    pub nodes: usize,
    /// Node features, `nodes × NODE_FEATURES`, row-major.
    pub features: Vec<f32>,
    /// Source node of each edge.
    pub src: Vec<u32>,
    /// Destination node of each edge (messages flow src → dst).
    pub dst: Vec<u32>,
    /// Relation index of each edge (`0..RELATIONS`).
    pub rel: Vec<u8>,
    /// The edge's scalar distance feature (index 17), 0 for self-loops and temporal edges.
    pub dist: Vec<f32>,
}

impl Graph {
    /// The 18 edge features of edge `i` as the original builds them.
    pub fn edge_feature(&self, i: usize) -> [f32; EDGE_FEATURES] {
        let mut f = [0.0; EDGE_FEATURES];
        f[usize::from(self.rel[i])] = 1.0;
        f[EDGE_FEATURES - 1] = self.dist[i];
        f
    }

    /// Empty the graph, keeping its allocations.
    pub fn clear(&mut self) {
        self.nodes = 0;
        self.features.clear();
        self.src.clear();
        self.dst.clear();
        self.rel.clear();
        self.dist.clear();
    }
}
