//! SNGNN-v2's network (docs/spec.md 7.1): six edge-conditioned convolutions (DGL `NNConv`, Gilmer
//! et al.) with mean aggregation, ELU between them and ReLU at the end; only the room node's
//! output is read.
//!
//! An `NNConv(in → out)` layer turns each edge's 18 features into an `in × out` matrix W(e) with
//! a three-layer MLP (the "edge network") and sends the message `h_srcᵀ·W(e)` along the edge;
//! a node's new features are the mean of its incoming messages plus a bias. Every node has a
//! self-loop, so no node is without messages.
//!
//! This file holds the weights in the shapes the computation wants and the reference forward
//! pass ([`Model::forward_exact`]), which evaluates every edge network (with docs/spec.md 7.5's
//! exact first-layer column lookup). The fast pass of the reward, which never runs an edge network
//! per edge, is [`super::pieces`]; both share the message passing here ([`Model::forward_with`]).

use super::{Graph, LAYERS, Weights, ZERO_FEATURE_RELATION};
use crate::math;

/// Index of the distance in the edge feature vector.
const DIST_FEATURE: usize = super::EDGE_FEATURES - 1;

/// The widest layer input or output (node feature rows are stored at this stride).
pub const MAX_WIDTH: usize = 42;
/// The largest `in × out` of a layer (the first: 42 × 40).
pub const MAX_MATRIX: usize = 42 * 40;

/// The network's output for the room node: (q1, q2); the reward uses q1 (docs/spec.md 6.3).
pub type Output = [f32; 2];

/// One edge network: Linear(18 → a) → ReLU → Linear(a → b) → ReLU → Linear(b → in·out).
/// Weights row-major as PyTorch stores them, `(outputs, inputs)`.
#[derive(Debug, Clone)]
pub struct EdgeMlp {
    /// Input width of the convolution (rows of W(e)).
    pub inputs: usize,
    /// Output width of the convolution (columns of W(e)).
    pub outputs: usize,
    /// a: width of the first hidden layer.
    pub hidden1: usize,
    /// b: width of the second hidden layer.
    pub hidden2: usize,
    /// `hidden1 × 18`.
    pub w1: Vec<f32>,
    /// `hidden1`.
    pub b1: Vec<f32>,
    /// `hidden2 × hidden1`.
    pub w2: Vec<f32>,
    /// `hidden2`.
    pub b2: Vec<f32>,
    /// `(inputs·outputs) × hidden2`; output row `i·outputs + o` is `W(e)[i][o]`.
    pub w3: Vec<f32>,
    /// `inputs·outputs`.
    pub b3: Vec<f32>,
}

impl EdgeMlp {
    fn new(w: &Weights, prefix: &str, inputs: usize, outputs: usize) -> Self {
        let t = |name: &str| w.get(&format!("{prefix}.edge_func.{name}"));
        let hidden1 = t("0.bias").data.len();
        let hidden2 = t("2.bias").data.len();
        EdgeMlp {
            inputs,
            outputs,
            hidden1,
            hidden2,
            w1: t("0.weight").data.clone(),
            b1: t("0.bias").data.clone(),
            w2: t("2.weight").data.clone(),
            b2: t("2.bias").data.clone(),
            w3: t("4.weight").data.clone(),
            b3: t("4.bias").data.clone(),
        }
    }

    /// `inputs × outputs`, the size of W(e).
    pub fn matrix_len(&self) -> usize {
        self.inputs * self.outputs
    }

    /// Pre-activation of the first hidden layer for an edge of relation `rel` and distance
    /// `dist`: the edge feature is a one-hot plus one scalar, so `W1·e + b1` is a column of W1,
    /// plus the distance column times `dist`, plus the bias (docs/spec.md 7.5). Relation 17's
    /// one-hot was overwritten by its zero distance, so it contributes no column.
    pub fn first_layer(&self, rel: u8, dist: f32, u: usize) -> f32 {
        let row = &self.w1[u * super::EDGE_FEATURES..(u + 1) * super::EDGE_FEATURES];
        let one_hot = if rel == ZERO_FEATURE_RELATION {
            0.0
        } else {
            row[usize::from(rel)]
        };
        one_hot + row[DIST_FEATURE] * dist + self.b1[u]
    }

    /// W(e) of an edge into `out[..inputs·outputs]`, in float32 like the original.
    pub fn eval(&self, rel: u8, dist: f32, z: &mut MlpScratch, out: &mut [f32]) {
        z.z1.clear();
        z.z1.extend((0..self.hidden1).map(|u| self.first_layer(rel, dist, u).max(0.0)));
        z.z2.clear();
        z.z2.extend(
            self.w2
                .chunks_exact(self.hidden1)
                .zip(&self.b2)
                .map(|(row, b)| (dot(row, &z.z1) + b).max(0.0)),
        );
        for ((o, row), b) in out
            .iter_mut()
            .zip(self.w3.chunks_exact(self.hidden2))
            .zip(&self.b3)
        {
            *o = dot(row, &z.z2) + b;
        }
    }
}

/// Hidden activations of one edge-network evaluation, reused.
#[derive(Debug, Clone, Default)]
pub struct MlpScratch {
    z1: Vec<f32>,
    z2: Vec<f32>,
}

/// What follows a layer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Activation {
    Elu,
    Relu,
}

/// One convolution: its edge network and node bias.
#[derive(Debug, Clone)]
pub struct Layer {
    /// The edge network.
    pub mlp: EdgeMlp,
    /// Added to the mean message, `outputs`.
    pub bias: Vec<f32>,
    activation: Activation,
}

/// The whole network, built once from the weights.
#[derive(Debug, Clone)]
pub struct Model {
    /// The six layers in order ([`LAYERS`]).
    pub layers: Vec<Layer>,
}

/// Node features and message sums of one forward pass, reused across graphs.
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    h: Vec<f32>,
    sums: Vec<f32>,
    degree: Vec<f32>,
    /// What the message function may use.
    pub edge: EdgeScratch,
}

/// Scratch of one edge's message: W(e) and the edge network's activations.
#[derive(Debug, Clone, Default)]
pub struct EdgeScratch {
    /// W(e), `inputs × outputs`.
    pub matrix: Vec<f32>,
    /// Edge-network activations.
    pub mlp: MlpScratch,
}

/// One edge of one layer, as the message function sees it.
#[derive(Debug, Clone, Copy)]
pub struct EdgeInput<'a> {
    /// Layer index into [`Model::layers`].
    pub layer: usize,
    /// Relation.
    pub rel: u8,
    /// Distance feature.
    pub dist: f32,
    /// The source node's features (`inputs`).
    pub h: &'a [f32],
}

impl Model {
    /// The network from loaded weights (names and shapes were checked by the loader).
    pub fn new(w: &Weights) -> Self {
        let layers = LAYERS
            .iter()
            .enumerate()
            .map(|(i, l)| Layer {
                mlp: EdgeMlp::new(w, l.name, l.inputs, l.outputs),
                bias: w.get(&format!("{}.bias", l.name)).data.clone(),
                activation: if i + 1 == LAYERS.len() {
                    Activation::Relu
                } else {
                    Activation::Elu
                },
            })
            .collect();
        Model { layers }
    }

    /// The reference forward pass: every edge's W(e) from its edge network.
    pub fn forward_exact(&self, g: &Graph, s: &mut Scratch) -> Output {
        self.forward_with(g, s, |e, sums, scratch| {
            self.add_exact_message(e, sums, scratch)
        })
    }

    /// `sums += hᵀ·W(e)` with W(e) from the edge network.
    pub fn add_exact_message(&self, e: EdgeInput<'_>, sums: &mut [f32], s: &mut EdgeScratch) {
        let mlp = &self.layers[e.layer].mlp;
        s.matrix.resize(mlp.matrix_len(), 0.0);
        mlp.eval(e.rel, e.dist, &mut s.mlp, &mut s.matrix);
        add_message(e.h, &s.matrix, sums);
    }

    /// The forward pass with the messages added by `message(edge, sums_of_dst, scratch)`.
    pub fn forward_with(
        &self,
        g: &Graph,
        s: &mut Scratch,
        mut message: impl FnMut(EdgeInput<'_>, &mut [f32], &mut EdgeScratch),
    ) -> Output {
        let n = g.nodes;
        s.h.clear();
        s.h.extend_from_slice(&g.features[..n * MAX_WIDTH]);
        s.degree.clear();
        s.degree.resize(n, 0.0);
        for &d in &g.dst {
            s.degree[d as usize] += 1.0;
        }
        for (li, layer) in self.layers.iter().enumerate() {
            let (inputs, outputs) = (layer.mlp.inputs, layer.mlp.outputs);
            s.sums.clear();
            s.sums.resize(n * outputs, 0.0);
            for e in 0..g.src.len() {
                let src = g.src[e] as usize * MAX_WIDTH;
                let dst = g.dst[e] as usize * outputs;
                let edge = EdgeInput {
                    layer: li,
                    rel: g.rel[e],
                    dist: g.dist[e],
                    h: &s.h[src..src + inputs],
                };
                message(edge, &mut s.sums[dst..dst + outputs], &mut s.edge);
            }
            for v in 0..n {
                let row = &mut s.h[v * MAX_WIDTH..(v + 1) * MAX_WIDTH];
                let sums = &s.sums[v * outputs..(v + 1) * outputs];
                for (o, x) in row.iter_mut().enumerate() {
                    *x = if o < outputs {
                        layer
                            .activation
                            .apply(sums[o] / s.degree[v] + layer.bias[o])
                    } else {
                        0.0
                    };
                }
            }
        }
        [s.h[0], s.h[1]]
    }
}

impl Activation {
    fn apply(self, x: f32) -> f32 {
        match self {
            Activation::Relu => x.max(0.0),
            // ELU with α = 1 (PyTorch's default).
            Activation::Elu if x > 0.0 => x,
            Activation::Elu => math::exp(x) - 1.0,
        }
    }
}

/// `sums += hᵀ·W` for a row vector `h` (`inputs`) and `W` (`inputs × outputs`, row-major).
pub fn add_message(h: &[f32], matrix: &[f32], sums: &mut [f32]) {
    let outputs = sums.len();
    for (hi, row) in h.iter().zip(matrix.chunks_exact(outputs)) {
        if *hi == 0.0 {
            continue;
        }
        for (s, w) in sums.iter_mut().zip(row) {
            *s += hi * w;
        }
    }
}

fn dot(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
