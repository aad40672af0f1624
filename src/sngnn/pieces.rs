//! SNGNN-v2's edge weights as piecewise-linear functions of the distance: the fast, exact
//! restructuring that makes the reward cheap (docs/spec.md, targets).
//!
//! An edge's feature is the one-hot of its relation plus one distance d, so for a fixed relation
//! the edge network is a function of d alone: z1 = ReLU(c + g·d) is piecewise linear in d with a
//! kink where a unit changes sign; inside each such interval z2 = ReLU(W2·z1 + b2) is linear in d
//! until one of its units changes sign; and W(e) = W3·z2 + b3 is linear in z2. So W(e) is
//! exactly linear between consecutive kinks ("knots"). The table keeps W at every knot of
//! `[0, max_dist]`, computed once in float64, and an edge's matrix is the linear interpolation
//! between the two knots around its distance: ~1,700 multiply-adds (first layer) instead of the
//! edge network's 2.5 million, with the same result up to rounding (the tests bound it against
//! the reference pass and the recorded outputs).
//!
//! Edges at distance 0 (self-loops, temporal edges) share one constant matrix per relation.
//! A distance outside the table (beyond `max_dist`, or not finite) falls back to the edge
//! network, so the result never depends on the table's range, only the speed does.

use ndarray::{Array2, ArrayView2, Axis};
use rayon::prelude::*;

use super::model::{EdgeInput, EdgeMlp, EdgeScratch, Model, Output, Scratch, add_message};
use super::{Graph, RELATIONS};

/// The self-loop relation: its distance is always 0 (docs/spec.md 7.3).
const SELF_RELATION: u8 = 11;
/// The spatial relations (one-hot positions 0-13); the temporal ones (14-17) have distance 0.
const SPATIAL_RELATIONS: u8 = 14;

/// W(e) of every layer as a function of (relation, distance).
#[derive(Debug, Clone)]
pub struct Tables {
    layers: Vec<LayerTable>,
    max_dist: f32,
}

#[derive(Debug, Clone)]
struct LayerTable {
    /// `inputs × outputs`.
    len: usize,
    /// W at distance 0 of every relation, `RELATIONS × len`.
    at_zero: Vec<f32>,
    /// Per relation: the knots of a spatial relation; `None` for relations whose distance is
    /// always 0.
    spatial: Vec<Option<Knots>>,
}

/// W sampled at the kinks of one relation's edge network.
#[derive(Debug, Clone)]
struct Knots {
    /// Increasing distances, the first 0 and the last the table's range.
    at: Vec<f32>,
    /// W at each knot, `at.len() × len`.
    values: Vec<f32>,
}

impl Tables {
    /// Tables of every layer for distances in `[0, max_dist]` (longer ones take the slow path).
    /// Costs a few float64 matrix products per layer and relation, spread over rayon's threads.
    pub fn new(model: &Model, max_dist: f32) -> Self {
        let layers = model
            .layers
            .par_iter()
            .map(|layer| LayerTable::new(&layer.mlp, f64::from(max_dist)))
            .collect();
        Tables { layers, max_dist }
    }

    /// The largest distance the tables cover.
    pub fn max_dist(&self) -> f32 {
        self.max_dist
    }

    /// Number of stored floats (the tables' memory is four bytes each).
    pub fn floats(&self) -> usize {
        self.layers
            .iter()
            .map(|l| {
                l.at_zero.len()
                    + l.spatial
                        .iter()
                        .flatten()
                        .map(|k| k.at.len() + k.values.len())
                        .sum::<usize>()
            })
            .sum()
    }

    /// The network's output for `g`, with every W(e) from the tables.
    pub fn forward(&self, model: &Model, g: &Graph, s: &mut Scratch) -> Output {
        model.forward_with(g, s, |e, sums, scratch| {
            self.add_message(model, e, sums, scratch)
        })
    }

    /// W(e) of layer `layer` for (`rel`, `dist`) as the tables give it, into `out`
    /// (`inputs × outputs`); `None` where the edge takes the edge network instead.
    pub fn matrix(&self, layer: usize, rel: u8, dist: f32, out: &mut [f32]) -> Option<()> {
        let table = &self.layers[layer];
        let len = table.len;
        match self.lookup(table, rel, dist)? {
            Lookup::Constant(w) => out[..len].copy_from_slice(w),
            Lookup::Between(lo, hi, t) => {
                for ((o, l), h) in out.iter_mut().zip(lo).zip(hi) {
                    *o = l * (1.0 - t) + h * t;
                }
            }
        }
        Some(())
    }

    /// Where W(e) comes from: a constant, two knots, or (`None`) the edge network.
    fn lookup<'t>(&'t self, table: &'t LayerTable, rel: u8, dist: f32) -> Option<Lookup<'t>> {
        let len = table.len;
        let rel = usize::from(rel);
        if dist == 0.0 {
            return Some(Lookup::Constant(&table.at_zero[rel * len..(rel + 1) * len]));
        }
        let knots = table.spatial.get(rel)?.as_ref()?;
        // Also false for NaN: a non-finite distance takes the edge network like the original.
        if !(dist > 0.0 && dist < self.max_dist) {
            return None;
        }
        let (k, t) = knots.locate(dist);
        Some(Lookup::Between(
            &knots.values[k * len..(k + 1) * len],
            &knots.values[(k + 1) * len..(k + 2) * len],
            t,
        ))
    }

    /// `sums += hᵀ·W(e)`.
    fn add_message(&self, model: &Model, e: EdgeInput<'_>, sums: &mut [f32], s: &mut EdgeScratch) {
        match self.lookup(&self.layers[e.layer], e.rel, e.dist) {
            Some(Lookup::Constant(w)) => add_message(e.h, w, sums),
            Some(Lookup::Between(lo, hi, t)) => add_interpolated_message(e.h, lo, hi, t, sums),
            None => model.add_exact_message(e, sums, s),
        }
    }
}

/// Word positions in a relation's entry of [`FlatLayer::index`].
pub mod flat {
    /// Offset in [`super::FlatLayer::floats`] of the relation's matrix at distance 0.
    pub const ZERO: usize = 0;
    /// Number of knots (0: the relation's distance is always 0, any other takes the edge
    /// network).
    pub const KNOTS: usize = 1;
    /// Offset of the knots' distances (increasing).
    pub const AT: usize = 2;
    /// Offset of the first knot's matrix; knot `k`'s is `len` floats further per `k`.
    pub const VALUES: usize = 3;
    /// Words per relation.
    pub const WORDS: usize = 4;
}

/// One layer's tables as one float array and an index, the form a device reads them in
/// ([`Tables::flat_layer`]). Matrices are `inputs × outputs`, row-major, as on the CPU.
#[derive(Debug, Clone, PartialEq)]
pub struct FlatLayer {
    /// Every stored matrix and knot distance of the layer.
    pub floats: Vec<f32>,
    /// [`flat::WORDS`] words per relation (`RELATIONS` of them): where its values lie in
    /// `floats`.
    pub index: Vec<u32>,
}

impl Tables {
    /// Number of layers.
    pub fn layers(&self) -> usize {
        self.layers.len()
    }

    /// Layer `layer`'s tables flattened: the 18 matrices at distance 0 first, then each
    /// spatial relation's knot distances and knot matrices. The values are the very floats the
    /// CPU reads, so a device that interpolates them the same way gets the same bits.
    #[expect(
        clippy::expect_used,
        reason = "a layer's tables stay far below 2^32 floats"
    )]
    pub fn flat_layer(&self, layer: usize) -> FlatLayer {
        let table = &self.layers[layer];
        let word = |n: usize| u32::try_from(n).expect("a layer's tables stay below 2^32 floats");
        let mut floats = table.at_zero.clone();
        let mut index = Vec::with_capacity(RELATIONS * flat::WORDS);
        for (rel, knots) in table.spatial.iter().enumerate() {
            let mut entry = [word(rel * table.len), 0, 0, 0];
            if let Some(k) = knots {
                entry[flat::KNOTS] = word(k.at.len());
                entry[flat::AT] = word(floats.len());
                floats.extend_from_slice(&k.at);
                entry[flat::VALUES] = word(floats.len());
                floats.extend_from_slice(&k.values);
            }
            index.extend_from_slice(&entry);
        }
        FlatLayer { floats, index }
    }
}

/// The source of one W(e).
enum Lookup<'t> {
    /// One stored matrix.
    Constant(&'t [f32]),
    /// `(1 − t)·lo + t·hi`.
    Between(&'t [f32], &'t [f32], f32),
}

impl Knots {
    /// The knot interval holding `d` (0 <= d < the last knot) and the position in it.
    fn locate(&self, d: f32) -> (usize, f32) {
        let k = self
            .at
            .partition_point(|&x| x <= d)
            .clamp(1, self.at.len() - 1)
            - 1;
        let (a, b) = (self.at[k], self.at[k + 1]);
        (k, (d - a) / (b - a))
    }
}

/// `sums += hᵀ·((1 − t)·lo + t·hi)`, the interpolated matrix never formed.
fn add_interpolated_message(h: &[f32], lo: &[f32], hi: &[f32], t: f32, sums: &mut [f32]) {
    let outputs = sums.len();
    for ((hi_in, lo_row), hi_row) in h
        .iter()
        .zip(lo.chunks_exact(outputs))
        .zip(hi.chunks_exact(outputs))
    {
        if *hi_in == 0.0 {
            continue;
        }
        let (a, b) = (hi_in * (1.0 - t), hi_in * t);
        for ((s, l), u) in sums.iter_mut().zip(lo_row).zip(hi_row) {
            *s += a * l + b * u;
        }
    }
}

/// An edge network's weights in float64, in the shapes the products want.
struct Mlp64<'a> {
    mlp: &'a EdgeMlp,
    w2: Array2<f64>,
    b2: Vec<f64>,
    w3: Array2<f64>,
    b3: Vec<f64>,
}

impl<'a> Mlp64<'a> {
    #[expect(
        clippy::expect_used,
        reason = "weight shapes are validated when the weights load"
    )]
    fn new(mlp: &'a EdgeMlp) -> Self {
        let widen = |v: &[f32]| v.iter().map(|&x| f64::from(x)).collect::<Vec<f64>>();
        let matrix = |v: &[f32], rows: usize, cols: usize| {
            Array2::from_shape_vec((rows, cols), widen(v)).expect("edge network weight shape")
        };
        Mlp64 {
            mlp,
            w2: matrix(&mlp.w2, mlp.hidden2, mlp.hidden1),
            b2: widen(&mlp.b2),
            w3: matrix(&mlp.w3, mlp.matrix_len(), mlp.hidden2),
            b3: widen(&mlp.b3),
        }
    }

    /// First hidden layer pre-activation `c + g·d` of relation `rel`: (c, g).
    fn first_layer(&self, rel: u8) -> (Vec<f64>, Vec<f64>) {
        let c = (0..self.mlp.hidden1)
            .map(|u| f64::from(self.mlp.first_layer(rel, 0.0, u)))
            .collect();
        let g = (0..self.mlp.hidden1)
            .map(|u| f64::from(self.mlp.w1[u * super::EDGE_FEATURES + super::EDGE_FEATURES - 1]))
            .collect();
        (c, g)
    }

    /// W = W3·z2 + b3 for each row of `z2` (`k × hidden2`), as `k × len` float32.
    fn matrices(&self, z2: ArrayView2<'_, f64>) -> Vec<f32> {
        let mut w = z2.dot(&self.w3.t());
        for mut row in w.axis_iter_mut(Axis(0)) {
            for (x, b) in row.iter_mut().zip(&self.b3) {
                *x += b;
            }
        }
        w.iter().map(|&x| x as f32).collect()
    }
}

impl LayerTable {
    fn new(mlp: &EdgeMlp, max_dist: f64) -> Self {
        let m = Mlp64::new(mlp);
        let at_zero = (0..RELATIONS as u8)
            .flat_map(|rel| {
                let (c, _) = m.first_layer(rel);
                let z1: Vec<f64> = c.iter().map(|&x| x.max(0.0)).collect();
                let z2 = hidden2(&m, &z1, &vec![0.0; z1.len()], 0.0);
                m.matrices(z2.view().insert_axis(Axis(0)))
            })
            .collect();
        let spatial = (0..RELATIONS as u8)
            .map(|rel| {
                let varies = rel < SPATIAL_RELATIONS && rel != SELF_RELATION;
                varies.then(|| Knots::new(&m, rel, max_dist))
            })
            .collect();
        LayerTable {
            len: mlp.matrix_len(),
            at_zero,
            spatial,
        }
    }
}

/// z2 at distance `d` inside an interval where z1 = α + β·d exactly.
fn hidden2(m: &Mlp64<'_>, alpha1: &[f64], beta1: &[f64], d: f64) -> ndarray::Array1<f64> {
    let z1: Vec<f64> = alpha1.iter().zip(beta1).map(|(a, b)| a + b * d).collect();
    let mut z2 = m.w2.dot(&ndarray::Array1::from(z1));
    for (x, b) in z2.iter_mut().zip(&m.b2) {
        *x = (*x + b).max(0.0);
    }
    z2
}

impl Knots {
    #[expect(
        clippy::expect_used,
        reason = "the rows are built as at.len() x b just above"
    )]
    fn new(m: &Mlp64<'_>, rel: u8, max_dist: f64) -> Self {
        let (c, g) = m.first_layer(rel);
        let bounds = first_layer_bounds(&c, &g, max_dist);
        let intervals = bounds.len() - 1;
        // z1 = α1 + β1·d inside each interval: the active units' (c, g), zeros elsewhere.
        let a = c.len();
        let mut alpha1 = Array2::<f64>::zeros((a, intervals));
        let mut beta1 = Array2::<f64>::zeros((a, intervals));
        for i in 0..intervals {
            let mid = 0.5 * (bounds[i] + bounds[i + 1]);
            for u in 0..a {
                if c[u] + g[u] * mid > 0.0 {
                    alpha1[[u, i]] = c[u];
                    beta1[[u, i]] = g[u];
                }
            }
        }
        // z2's pre-activation = α2 + β2·d inside each interval.
        let mut alpha2 = m.w2.dot(&alpha1);
        for mut col in alpha2.axis_iter_mut(Axis(1)) {
            for (x, b) in col.iter_mut().zip(&m.b2) {
                *x += b;
            }
        }
        let beta2 = m.w2.dot(&beta1);
        let mut at: Vec<f64> = Vec::new();
        let mut rows: Vec<f64> = Vec::new();
        let b = alpha2.nrows();
        for i in 0..intervals {
            let (lo, hi) = (bounds[i], bounds[i + 1]);
            let (a2, b2) = (alpha2.column(i), beta2.column(i));
            let mut knots = vec![lo];
            knots.extend(
                a2.iter()
                    .zip(b2.iter())
                    .filter(|&(_, &slope)| slope != 0.0)
                    .map(|(&a, &slope)| -a / slope)
                    .filter(|&d| d > lo && d < hi),
            );
            if i + 1 == intervals {
                knots.push(hi);
            }
            knots.sort_by(f64::total_cmp);
            for d in knots {
                at.push(d);
                rows.extend(a2.iter().zip(b2.iter()).map(|(a, s)| (a + s * d).max(0.0)));
            }
        }
        let z2 = Array2::from_shape_vec((at.len(), b), rows).expect("knot rows");
        let values = m.matrices(z2.view());
        Knots::from_f64(at, values, m.mlp.matrix_len())
    }

    /// Round the knots to float32 and drop any that collapses onto its predecessor (an interval
    /// narrower than float32 resolution changes nothing measurable).
    fn from_f64(at: Vec<f64>, values: Vec<f32>, len: usize) -> Self {
        let mut knots = Knots {
            at: Vec::with_capacity(at.len()),
            values: Vec::with_capacity(values.len()),
        };
        for (k, &d) in at.iter().enumerate() {
            let d = d as f32;
            if knots.at.last().is_some_and(|&last| d <= last) {
                continue;
            }
            knots.at.push(d);
            knots
                .values
                .extend_from_slice(&values[k * len..(k + 1) * len]);
        }
        knots
    }
}

/// 0, every distance in (0, max_dist) where a first-layer unit changes sign, and max_dist.
fn first_layer_bounds(c: &[f64], g: &[f64], max_dist: f64) -> Vec<f64> {
    let mut bounds = vec![0.0];
    bounds.extend(
        c.iter()
            .zip(g)
            .filter(|&(_, &slope)| slope != 0.0)
            .map(|(&c, &slope)| -c / slope)
            .filter(|&d| d > 0.0 && d < max_dist),
    );
    bounds.push(max_dist);
    bounds.sort_by(f64::total_cmp);
    bounds.dedup();
    bounds
}
