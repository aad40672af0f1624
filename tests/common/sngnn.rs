//! SNGNN-v2 test helpers: the real weights (skipped loudly without them unless
//! `REQUIRE_SNGNN=1`) and the golden graph dumps as [`Graph`]s.

use std::collections::BTreeMap;
use std::path::Path;

use socnav::sngnn::{self, EDGE_FEATURES, Graph, Weights};

use super::npz::{Array, read_npz};

/// The real weights, or `None` (with the reason printed) when they are not installed.
pub fn real_weights() -> Option<Weights> {
    let path = sngnn::weights_path(None).path;
    if !path.is_file() {
        let why = format!(
            "no SNGNN-v2 weights at {}: install them with `socnav sngnn install`",
            path.display()
        );
        if std::env::var("REQUIRE_SNGNN").is_ok_and(|v| v == "1") {
            panic!("REQUIRE_SNGNN=1 but {why}");
        }
        eprintln!("SKIPPED: {why}");
        return None;
    }
    Some(Weights::load(&path).expect("the installed weights load"))
}

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
