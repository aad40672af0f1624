//! SNGNN-v2 on the device (`backend::gpu::GpuNet`, `shaders/sngnn_score.wgsl`) against the CPU's
//! tables pass (`Tables::forward`): the recorded graphs of the golden SNGNN episodes with the
//! real weights (also within 1e-4 of 0.1.1's recorded outputs), and random graphs with random
//! weights of the real shapes. On lavapipe the device sums in the CPU's order with the same
//! operations, so the outputs are compared bit for bit there; other adapters get a tolerance.
//!
//! Needs a GPU adapter (lavapipe will do) and, for the golden graphs, the weights; without
//! them the tests print why and pass, unless `REQUIRE_GPU=1` / `REQUIRE_SNGNN=1`.

use crate::common;
use crate::golden;

use common::sngnn::{GOLDEN, GOLDEN_TOLERANCE, Rand, random_graph, random_weights};
use socnav::Config;
use socnav::backend::gpu::GpuDevice;
use socnav::backend::gpu::GpuNet;
use socnav::sngnn::model::{Model, Output, Scratch};
use socnav::sngnn::packed::PackedLayout;
use socnav::sngnn::pieces::Tables;
use socnav::sngnn::{Graph, table_range};

/// Relative bound on a hardware GPU, which may contract `a·b + c` and round `exp` and division
/// differently.
const HARDWARE_TOLERANCE: f32 = 1e-4;

/// Pack `graphs` into one batch of `layout`.
fn pack(layout: &PackedLayout, graphs: &[&Graph]) -> (Vec<u32>, Vec<f32>) {
    let (su, sf) = (layout.u32_stride(), layout.f32_stride());
    let mut u = vec![0; graphs.len() * su];
    let mut f = vec![0.0; graphs.len() * sf];
    for (k, g) in graphs.iter().enumerate() {
        layout
            .pack(
                g,
                &mut u[k * su..(k + 1) * su],
                &mut f[k * sf..(k + 1) * sf],
            )
            .expect("pack");
    }
    (u, f)
}

/// Whether the adapter is lavapipe, where the outputs must equal the CPU's bits.
fn exact(dev: &GpuDevice) -> bool {
    !dev.adapter.hardware
}

/// Score `graphs` on the device (one batch) and on the CPU; returns the device outputs after
/// checking them against the CPU's: bit for bit on lavapipe, within a tolerance elsewhere.
/// Prints the largest difference and the forward's time.
fn compare(dev: &GpuDevice, model: &Model, tables: &Tables, graphs: &[&Graph]) -> Vec<Output> {
    let layout = PackedLayout::fitting(graphs.iter().copied());
    let (u, f) = pack(&layout, graphs);
    let mut net = GpuNet::new(dev.clone(), model, tables, layout, graphs.len()).expect("net");
    net.upload(&u, &f).expect("upload");
    let mut out = vec![[0.0; 2]; graphs.len()];
    let per = net.time_forward(&mut out, 5).expect("forward");
    let mut s = Scratch::default();
    let start = std::time::Instant::now();
    let cpu: Vec<Output> = graphs
        .iter()
        .map(|g| tables.forward(model, g, &mut s))
        .collect();
    let cpu_time = start.elapsed();
    let (mut worst, mut differing) = (0.0f32, 0);
    for (k, (g, cpu)) in graphs.iter().zip(&cpu).enumerate() {
        for j in 0..2 {
            let (a, b) = (out[k][j], cpu[j]);
            worst = worst.max((a - b).abs());
            differing += usize::from(a.to_bits() != b.to_bits());
            if exact(dev) {
                assert_eq!(
                    a.to_bits(),
                    b.to_bits(),
                    "graph {k} ({} nodes, {} edges) output {j}: device {a} CPU {b}",
                    g.nodes,
                    g.src.len()
                );
            } else {
                let tolerance = HARDWARE_TOLERANCE * b.abs().max(1.0);
                assert!(
                    (a - b).abs() <= tolerance,
                    "graph {k} output {j}: device {a} CPU {b}"
                );
            }
        }
    }
    eprintln!(
        "{}: {} graphs (layout {} nodes, {} edges): {differing} outputs differ from the CPU's \
         bits, largest difference {worst:e}; forward {per:?} per batch (CPU tables pass, one \
         thread: {cpu_time:?})",
        dev.adapter,
        graphs.len(),
        layout.max_nodes,
        layout.max_edges
    );
    out
}

#[test]
fn golden_graphs_on_the_device() {
    let Some(dev) = common::gpu::device() else {
        return;
    };
    let Some(weights) = common::sngnn::real_weights() else {
        return;
    };
    let model = Model::new(&weights);
    let range = ["exp1_sngnn", "exp2_sngnn"]
        .iter()
        .map(|c| table_range(&Config::from_name_or_path(c).expect("config")))
        .fold(0.0, f32::max);
    let tables = Tables::new(&model, range);
    let largest = (0..tables.layers())
        .map(|l| tables.flat_layer(l).floats.len())
        .max()
        .unwrap_or(0);
    eprintln!(
        "tables to {range} (10 m units): {} MB in all, {} MB in the largest layer",
        tables.floats() * 4 / 1_000_000,
        largest * 4 / 1_000_000
    );
    let dir = golden::published_dir();
    let goldens: Vec<_> = GOLDEN
        .iter()
        .flat_map(|&(config, seed)| common::sngnn::golden_graphs(&dir, config, seed))
        .collect();
    assert_eq!(goldens.len(), 18, "three graphs per episode");
    let graphs: Vec<&Graph> = goldens.iter().map(|g| &g.graph).collect();
    let out = compare(&dev, &model, &tables, &graphs);
    let mut worst = 0.0f32;
    for (golden, got) in goldens.iter().zip(&out) {
        for (&a, &b) in got.iter().zip(&golden.output) {
            worst = worst.max((a - b).abs());
            assert!(
                (a - b).abs() <= GOLDEN_TOLERANCE,
                "step {}: device {a}, 0.1.1 recorded {b}",
                golden.step
            );
        }
    }
    eprintln!("largest difference from 0.1.1's recorded outputs: {worst:e}");
}

#[test]
fn random_graphs_on_the_device() {
    let Some(dev) = common::gpu::device() else {
        return;
    };
    let model = Model::new(&random_weights(8));
    let tables = Tables::new(&model, 1.5);
    let mut r = Rand(9);
    // Sizes vary so that the padding of the layout is exercised; distances stay in the tables.
    let graphs: Vec<Graph> = (0..8)
        .map(|k| random_graph(&mut r, 10 + 7 * k, 30 + 25 * k, 1.45))
        .collect();
    let refs: Vec<&Graph> = graphs.iter().collect();
    compare(&dev, &model, &tables, &refs);
}

/// An edge the tables do not cover is an error on the device, which has no edge network.
#[test]
fn distances_outside_the_tables_are_reported() {
    let Some(dev) = common::gpu::device() else {
        return;
    };
    let model = Model::new(&random_weights(10));
    let tables = Tables::new(&model, 0.5);
    let mut g = random_graph(&mut Rand(11), 6, 10, 0.4);
    g.src.push(0);
    g.dst.push(1);
    g.rel.push(5);
    g.dist.push(0.75);
    let layout = PackedLayout::fitting([&g]);
    let (u, f) = pack(&layout, &[&g]);
    let mut net = GpuNet::new(dev, &model, &tables, layout, 1).expect("net");
    net.upload(&u, &f).expect("upload");
    let e = net.forward(&mut [[0.0; 2]]).unwrap_err();
    assert!(
        e.to_string().contains("outside the edge-weight tables"),
        "{e}"
    );
}

/// A graph the layout cannot hold is reported, not scored; an empty one is skipped (NaN).
#[test]
fn invalid_graphs_are_reported() {
    let Some(dev) = common::gpu::device() else {
        return;
    };
    let model = Model::new(&random_weights(12));
    let tables = Tables::new(&model, 1.5);
    let g = random_graph(&mut Rand(13), 5, 8, 1.0);
    let layout = PackedLayout::fitting([&g]);
    let (mut u, f) = pack(&layout, &[&g]);
    let mut net = GpuNet::new(dev, &model, &tables, layout, 1).expect("net");
    // A destination beyond the graph's nodes.
    u[socnav::sngnn::packed::words::SRC + layout.max_edges] = 5;
    net.upload(&u, &f).expect("upload");
    let e = net.forward(&mut [[0.0; 2]]).unwrap_err();
    assert!(e.to_string().contains("names a node or relation"), "{e}");
    // No nodes at all: nothing to score, and no error.
    u.fill(0);
    net.upload(&u, &f).expect("upload");
    let mut out = [[0.0; 2]];
    net.forward(&mut out).expect("an empty graph is skipped");
    assert!(out[0].iter().all(|q| q.is_nan()), "{out:?}");
}
