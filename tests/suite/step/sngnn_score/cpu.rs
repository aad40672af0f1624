//! SNGNN-v2 inference (docs/spec.md 7.1, 7.5): the piecewise-linear edge-weight tables against the
//! edge networks they replace, and both forward passes against each other, on random weights of the
//! real shapes (these tests need no weight file).
//!
//! Tolerances: the tables hold W(e) computed in float64 at the edge network's kinks and
//! interpolate linearly between them, which is exact algebra; what remains is float32 rounding
//! of the stored values and of the interpolation, and float32 rounding inside the reference
//! edge network (sums of up to 1,124 products). Both are a few ulps of the largest entries.

use crate::common;
use crate::golden;

use common::sngnn::{GOLDEN, GOLDEN_TOLERANCE, Rand, random_graph, random_weights};
use socnav::sngnn::model::{EdgeMlp, MAX_WIDTH, Model, Scratch};
use socnav::sngnn::pieces::Tables;
use socnav::sngnn::{NODE_FEATURES, RELATIONS};

/// The largest absolute entry of an edge network's output over a few distances, the scale the
/// tolerances are relative to.
fn scale(mlp: &EdgeMlp, rel: u8) -> f32 {
    let mut out = vec![0.0; mlp.matrix_len()];
    let mut z = Default::default();
    [0.0, 0.5, 1.0, 1.5]
        .iter()
        .map(|&d| {
            mlp.eval(rel, d, &mut z, &mut out);
            out.iter().fold(0.0f32, |m, x| m.max(x.abs()))
        })
        .fold(0.0, f32::max)
}

#[test]
fn tables_reproduce_the_edge_networks() {
    let model = Model::new(&random_weights(1));
    let max_dist = 1.5;
    let tables = Tables::new(&model, max_dist);
    let mut r = Rand(2);
    let mut exact = vec![0.0; 42 * 40];
    let mut table = vec![0.0; 42 * 40];
    let mut z = Default::default();
    for (layer, l) in model.layers.iter().enumerate() {
        for rel in 0..RELATIONS as u8 {
            let tolerance = 2e-5 * scale(&l.mlp, rel);
            // Distance 0 for every relation (self-loops, temporal edges), random ones in range
            // for the spatial relations, and the knots' neighbourhood by sheer number.
            let mut dists = vec![0.0];
            if rel < 14 && rel != 11 {
                dists.extend((0..120).map(|_| r.uniform(0.0, max_dist)));
            }
            for d in dists {
                let n = l.mlp.matrix_len();
                l.mlp.eval(rel, d, &mut z, &mut exact[..n]);
                tables
                    .matrix(layer, rel, d, &mut table[..n])
                    .unwrap_or_else(|| panic!("layer {layer} rel {rel} d {d}: not in the tables"));
                for i in 0..n {
                    let diff = (exact[i] - table[i]).abs();
                    assert!(
                        diff <= tolerance,
                        "layer {layer} rel {rel} d {d} entry {i}: edge network {} tables {} (|diff| {diff:e} > {tolerance:e})",
                        exact[i],
                        table[i]
                    );
                }
            }
        }
    }
}

#[test]
fn distances_outside_the_tables_take_the_edge_network() {
    let model = Model::new(&random_weights(3));
    let tables = Tables::new(&model, 0.5);
    let mut out = vec![0.0; 42 * 40];
    assert!(
        tables.matrix(0, 5, 0.25, &mut out).is_some(),
        "inside the range"
    );
    for d in [0.5, 0.75, f32::INFINITY, f32::NAN, -0.1] {
        assert!(
            tables.matrix(0, 5, d, &mut out).is_none(),
            "distance {d} must take the edge network"
        );
    }
    // A temporal relation never has a distance: any non-zero one takes the edge network.
    assert!(tables.matrix(0, 14, 0.25, &mut out).is_none());
    assert!(tables.matrix(0, 14, 0.0, &mut out).is_some());
}

#[test]
fn fast_and_reference_forward_passes_agree() {
    assert_eq!(
        MAX_WIDTH, NODE_FEATURES,
        "node rows are stored at the input width"
    );
    let model = Model::new(&random_weights(4));
    let tables = Tables::new(&model, 1.5);
    let mut r = Rand(5);
    let mut s = Scratch::default();
    for case in 0..4 {
        // Distances up to 2 m: some spatial edges lie beyond the tables and take the slow path.
        let g = random_graph(&mut r, 40, 120, 2.0);
        let exact = model.forward_exact(&g, &mut s);
        let fast = tables.forward(&model, &g, &mut s);
        for k in 0..2 {
            let tolerance = 1e-5 * exact[k].abs().max(1.0);
            assert!(
                (exact[k] - fast[k]).abs() <= tolerance,
                "graph {case} output {k}: reference {} tables {}",
                exact[k],
                fast[k]
            );
        }
    }
}

/// Both forward passes on the graphs the original fed its network (steps 1, 2 and 25 of every
/// SNGNN episode: one, two and three stacked frames) give its recorded output within 1e-4.
#[test]
fn recorded_graphs_give_the_recorded_output() {
    let Some(weights) = common::sngnn::real_weights() else {
        return;
    };
    let model = Model::new(&weights);
    let tables = Tables::new(&model, 1.5);
    let mut s = Scratch::default();
    let dir = golden::published_dir();
    let mut worst = 0.0f32;
    for (config, seed) in GOLDEN {
        for golden in common::sngnn::golden_graphs(&dir, config, seed) {
            let g = &golden.graph;
            for e in 0..g.src.len() {
                let recorded = &golden.edge_feats[e * 18..(e + 1) * 18];
                assert_eq!(
                    g.edge_feature(e),
                    recorded,
                    "{config} seed {seed} step {}: edge {e}",
                    golden.step
                );
            }
            // The reference pass is slow (2.5 M multiply-adds per edge of the first layer):
            // one graph per episode, the three-frame one.
            let exact = (golden.step == 25).then(|| model.forward_exact(g, &mut s));
            let fast = tables.forward(&model, g, &mut s);
            for (pass, out) in [("tables", Some(fast)), ("reference", exact)] {
                let Some(out) = out else { continue };
                for (k, (&got, &want)) in out.iter().zip(&golden.output).enumerate() {
                    let diff = (got - want).abs();
                    worst = worst.max(diff);
                    assert!(
                        diff <= GOLDEN_TOLERANCE,
                        "{config} seed {seed} step {} ({} nodes, {} edges), {pass} pass: output {k} is {} where 0.1.1 gave {}",
                        golden.step,
                        g.nodes,
                        g.src.len(),
                        got,
                        want
                    );
                }
            }
        }
    }
    eprintln!("largest difference from the recorded outputs: {worst:e}");
}

/// The flat export a device reads (`Tables::flat_layer`) holds the very floats the CPU
/// interpolates: W(e) rebuilt from it matches `Tables::matrix` bit for bit.
#[test]
fn flat_tables_hold_the_cpu_tables() {
    use socnav::sngnn::pieces::flat;
    let model = Model::new(&random_weights(6));
    let tables = Tables::new(&model, 1.5);
    let mut r = Rand(7);
    let mut want = vec![0.0; 42 * 40];
    for (layer, l) in model.layers.iter().enumerate() {
        let f = tables.flat_layer(layer);
        let len = l.mlp.matrix_len();
        for rel in 0..RELATIONS as u8 {
            let entry = &f.index[usize::from(rel) * flat::WORDS..][..flat::WORDS];
            let zero = entry[flat::ZERO] as usize;
            tables.matrix(layer, rel, 0.0, &mut want).unwrap();
            assert_eq!(
                &f.floats[zero..zero + len],
                &want[..len],
                "layer {layer} rel {rel} at 0"
            );
            let knots = entry[flat::KNOTS] as usize;
            assert_eq!(
                knots == 0,
                rel >= 14 || rel == 11,
                "layer {layer} rel {rel}"
            );
            if knots == 0 {
                continue;
            }
            let at = &f.floats[entry[flat::AT] as usize..][..knots];
            for _ in 0..20 {
                let d = r.uniform(0.0, 1.5);
                let k = at.partition_point(|&x| x <= d).clamp(1, knots - 1) - 1;
                let t = (d - at[k]) / (at[k + 1] - at[k]);
                let lo = entry[flat::VALUES] as usize + k * len;
                tables.matrix(layer, rel, d, &mut want).unwrap();
                let (l, h) = (&f.floats[lo..lo + len], &f.floats[lo + len..lo + 2 * len]);
                for ((l, h), want) in l.iter().zip(h).zip(&want[..len]) {
                    let w = l * (1.0 - t) + h * t;
                    assert_eq!(w.to_bits(), want.to_bits(), "layer {layer} rel {rel} d {d}");
                }
            }
        }
    }
}
