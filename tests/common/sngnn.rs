//! SNGNN-v2 test helpers: the real weights (skipped loudly without them unless
//! `REQUIRE_SNGNN=1`) and the golden graph dumps as [`Graph`]s.

use std::collections::BTreeMap;
use std::path::Path;

use socnav::sngnn::{self, EDGE_FEATURES, Graph, LAYERS, NODE_FEATURES, Tensor, Weights};

use super::npz::{Array, read_npz};

/// The real weights, or `None` (with the reason printed) when they are not installed.
pub fn real_weights() -> Option<Weights> {
    let path = sngnn::weights_path(None).path;
    if !path.is_file() {
        let why = format!(
            "no SNGNN-v2 weights at {}: install them with `socnav sngnn install`",
            path.display()
        );
        super::skip::skip(Some("REQUIRE_SNGNN"), &why);
        return None;
    }
    Some(Weights::load(&path).expect("the installed weights load"))
}

/// `config` with the DSRNN reward where it has SNGNN-v2's: for tests about something other than
/// the reward (spawns, interaction pairs), which then run without the weight file.
pub fn without_sngnn_reward(mut config: socnav::Config) -> socnav::Config {
    if config.reward.kind == socnav::config::RewardKind::Sngnn {
        config.reward.kind = socnav::config::RewardKind::Dsrnn;
    }
    config
}

/// The six golden episodes with SNGNN graph dumps.
pub const GOLDEN: [(&str, usize); 6] = [
    ("exp1_with_sngnn", 0),
    ("exp1_with_sngnn", 1),
    ("exp1_with_sngnn", 2),
    ("exp2_with_sngnn", 0),
    ("exp2_with_sngnn", 1),
    ("exp2_with_sngnn", 2),
];

/// Issue 6's bound on the difference from the original's output.
pub const GOLDEN_TOLERANCE: f32 = 1e-4;

/// One dumped graph of a golden SNGNN episode: the graph, its 18-float edge features as
/// recorded, and the recorded output `[q1, q2]`.
pub struct GoldenGraph {
    pub step: usize,
    pub graph: Graph,
    pub edge_feats: Vec<f32>,
    pub output: [f32; 2],
}

/// The graphs dumped for `<config>_seed<seed>` (steps 1, 2 and 25) in the golden directory.
pub fn golden_graphs(dir: &Path, config: &str, seed: usize) -> Vec<GoldenGraph> {
    let arrays = read_npz(&dir.join(format!("{config}_seed{seed}_graphs.npz")));
    arrays["steps"]
        .usizes()
        .into_iter()
        .map(|step| golden_graph(&arrays, step))
        .collect()
}

fn golden_graph(a: &BTreeMap<String, Array>, step: usize) -> GoldenGraph {
    let f = |n: &str| &a[&format!("step{step}_{n}")];
    let edge_feats = f("edge_feats").f32s();
    let ids = |n: &str| f(n).usizes().into_iter().map(|x| x as u32).collect();
    let graph = Graph {
        nodes: f("node_feats").shape[0],
        features: f("node_feats").f32s(),
        src: ids("src"),
        dst: ids("dst"),
        rel: f("rel_type")
            .usizes()
            .into_iter()
            .map(|x| x as u8)
            .collect(),
        dist: edge_feats
            .chunks_exact(EDGE_FEATURES)
            .map(|c| c[EDGE_FEATURES - 1])
            .collect(),
    };
    let out = f("output").f32s();
    GoldenGraph {
        step,
        graph,
        edge_feats,
        output: [out[0], out[1]],
    }
}

/// A small deterministic generator (splitmix64) for test data.
pub struct Rand(pub u64);

impl Rand {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next() >> 40) as f32 / (1u64 << 24) as f32)
    }
}

/// Random weights with the real names and shapes (docs/spec.md 7.1), initialised like PyTorch's
/// `Linear` (uniform in ±1/√fan_in).
pub fn random_weights(seed: u64) -> Weights {
    let mut r = Rand(seed);
    let mut tensors = std::collections::BTreeMap::new();
    let mut add = |name: String, shape: Vec<usize>, fan_in: usize, r: &mut Rand| {
        let bound = 1.0 / (fan_in as f32).sqrt();
        let data = (0..shape.iter().product())
            .map(|_| r.uniform(-bound, bound))
            .collect();
        tensors.insert(name, Tensor { shape, data });
    };
    for layer in LAYERS {
        for (name, shape) in layer.tensors() {
            // A Linear weight is (out, in); a bias's fan-in is its layer's input width.
            let fan_in = if shape.len() == 2 {
                shape[1]
            } else {
                layer.inputs
            };
            add(name, shape, fan_in, &mut r);
        }
    }
    Weights { tensors }
}

/// A random graph shaped like SNGNN's: every node has a self-loop, plus random spatial edges
/// with distances in `[0, max_dist)` and temporal edges at distance 0.
pub fn random_graph(r: &mut Rand, nodes: usize, edges: usize, max_dist: f32) -> Graph {
    let mut g = Graph {
        nodes,
        ..Default::default()
    };
    g.features = (0..nodes * NODE_FEATURES)
        .map(|_| {
            if r.uniform(0.0, 1.0) < 0.3 {
                r.uniform(-1.0, 1.0)
            } else {
                0.0
            }
        })
        .collect();
    let mut edge = |src: usize, dst: usize, rel: u8, dist: f32| {
        g.src.push(src as u32);
        g.dst.push(dst as u32);
        g.rel.push(rel);
        g.dist.push(dist);
    };
    for v in 0..nodes {
        edge(v, v, 11, 0.0);
    }
    for _ in 0..edges {
        let src = (r.next() % nodes as u64) as usize;
        let dst = (r.next() % nodes as u64) as usize;
        let rel = (r.next() % 18) as u8;
        let dist = if rel < 14 && rel != 11 {
            r.uniform(0.0, max_dist)
        } else {
            0.0
        };
        edge(src, dst, rel, dist);
    }
    g
}
