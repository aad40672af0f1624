//! The device's SNGNN-v2 input against the CPU's, bit for bit (docs/spec.md, determinism): the pass
//! `sngnn_graph` (shaders/common/sngnn_frame.wgsl and sngnn_graph.wgsl) records the frame into
//! the history columns and builds the packed graph of every stepping, non-terminal environment;
//! the CPU does the same with `sngnn::frame::record`, `sngnn::graph::build` and
//! `PackedLayout::pack`.
//!
//! Batches of the shipped SNGNN configs are rolled out on the CPU without `BatchEnv` (so no
//! weights are needed: the stages score with the DSRNN reward, `common/sngnn_rollout.rs`); at
//! every step the state right after the reward stage is uploaded, both sides record and build,
//! and every state column and every word of the packed graphs is compared. The histories fill,
//! wrap and empty at resets; 256 environments.
//! Experiment 2 runs at dt = 0.5 s (a 7-frame history from which the graph skips frames, and a
//! time step other than 1 s, which would hide a misplaced factor of dt), and experiment 1 also
//! at dt = 0.1 s (a 25-frame history, frame gaps of 10 or 11 ticks as f64 rounding decides).
//!
//! Needs a GPU adapter (lavapipe will do); without one the tests say why and pass, unless
//! `REQUIRE_GPU=1`.

use crate::common;

use common::gpu::{
    Lockstep, Parity, TOLERANCE, device, first_differences, floats_agree, parity_mode, tally_column,
};
use common::sngnn_rollout::SngnnRollout;
use socnav::Config;
use socnav::backend::gpu::GpuStages;
use socnav::rng::RngStream;

const N_ENVS: usize = 256;

/// Roll `name` (at time step `dt`, s) out for `steps` steps, comparing the device's frame and
/// graph with the CPU's at each; with `every_relation`, the graphs must have held edges of every
/// relation (experiment 1 has no groups or laptops: no interaction edges).
fn check(name: &str, dt: f32, steps: usize, every_relation: bool) {
    let Some(dev) = device() else {
        return;
    };
    let mut config = Config::from_name_or_path(name).expect(name);
    config.episode.time_step = dt;
    let mut r = SngnnRollout::new(&config, N_ENVS, 11);
    let mut gpu = GpuStages::with_sngnn_graphs(dev, &r.p, &r.s, &r.o, &["sngnn_graph"], r.graphs)
        .expect("the SNGNN graph pass");
    let mut from_gpu = r.s.clone();
    let mut rng = RngStream::new(5, 2);
    let mut scored = 0;
    let mode = parity_mode(gpu.adapter());
    let mut lockstep = Lockstep::default();
    for step in 0..steps {
        let actions = r.random_actions(&mut rng);
        r.step_to_reward(&actions);
        gpu.upload_state(&r.s);
        gpu.upload_outputs(&r.o);
        scored += r.score();
        gpu.run("sngnn_graph").expect("the pass runs");
        gpu.download_state(&mut from_gpu).expect("readback");
        if mode == Parity::Lockstep {
            let in_state = lockstep.state_verdicts(N_ENVS, (&r.s, &from_gpu));
            let (gu, gf) = gpu
                .download_sngnn_graphs()
                .expect("readback")
                .expect("graph buffers");
            let in_graphs = graphs_diverged(&r, &gu, &gf);
            let graphs = in_graphs.iter().filter(|&&d| d).count();
            if graphs > 0 {
                tally_column(&mut lockstep.by_column, "packed graph", graphs);
            }
            let envs: Vec<bool> = in_state
                .iter()
                .zip(&in_graphs)
                .map(|(a, b)| *a || *b)
                .collect();
            lockstep.add_envs(&envs);
            r.finish_step(&actions);
            continue;
        }
        let differ = r.s.differing_columns(&from_gpu);
        assert!(
            differ.is_empty(),
            "{name} step {step}: state columns {differ:?} differ; first differences: {}",
            first_differences(
                &r.s.columns(),
                |f, u| r.s.pack(f, u),
                |f, u| from_gpu.pack(f, u)
            )
        );
        let (gu, gf) = gpu
            .download_sngnn_graphs()
            .expect("readback")
            .expect("graph buffers");
        compare_graphs(&r, &gu, &gf, &format!("{name} step {step}"));
        r.finish_step(&actions);
    }
    let (nodes, edges, frames) = r.largest;
    if mode == Parity::Lockstep {
        lockstep.check(
            &format!("{name} at dt {dt} s, frames and graphs"),
            gpu.adapter(),
        );
    } else {
        println!(
            "{name} at dt {dt} s: {scored} frames and graphs over {steps} steps bit-identical \
             (largest {nodes} nodes, {edges} edges, {frames} frames; capacity {:?})",
            r.graphs
        );
    }
    assert!(scored > N_ENVS && frames == 3, "{name}: three-frame graphs");
    println!("{name}: edges per relation {:?}", r.relations);
    assert!(
        !every_relation || r.relations.iter().all(|&n| n > 0),
        "{name}: every relation was built ({:?})",
        r.relations
    );
}

/// Per environment, whether its packed graph diverged from the CPU's: a word of its structure
/// differs (node and edge counts, edge endpoints and relations) or a feature beyond the tolerance.
fn graphs_diverged(r: &SngnnRollout, gu: &[u32], gf: &[f32]) -> Vec<bool> {
    let (us, fs) = (r.graphs.u32_stride(), r.graphs.f32_stride());
    (0..N_ENVS)
        .map(|e| {
            (e * us..(e + 1) * us).any(|i| gu[i] != r.packed_u32[i])
                || (e * fs..(e + 1) * fs).any(|i| !floats_agree(r.packed_f32[i], gf[i], TOLERANCE))
        })
        .collect()
}

/// Every word of every environment's packed graph, naming the first difference.
fn compare_graphs(r: &SngnnRollout, gu: &[u32], gf: &[f32], at: &str) {
    let (us, fs) = (r.graphs.u32_stride(), r.graphs.f32_stride());
    if let Some(i) = (0..gu.len()).find(|&i| gu[i] != r.packed_u32[i]) {
        panic!(
            "{at}: packed graph of environment {} differs at u32 word {}: cpu {} vs gpu {} \
             (CPU graph: {} nodes, {} edges)",
            i / us,
            i % us,
            r.packed_u32[i],
            gu[i],
            r.packed_u32[i / us * us],
            r.packed_u32[i / us * us + 1]
        );
    }
    if let Some(i) = (0..gf.len()).find(|&i| gf[i].to_bits() != r.packed_f32[i].to_bits()) {
        let nf = socnav::sngnn::NODE_FEATURES;
        let row = i / nf * nf;
        let others: Vec<String> = (row..row + nf)
            .filter(|&k| gf[k].to_bits() != r.packed_f32[k].to_bits())
            .map(|k| format!("{}: {:e} vs {:e}", k - row, r.packed_f32[k], gf[k]))
            .collect();
        eprintln!(
            "{at}: differing features of that row: {}",
            others.join(", ")
        );
        panic!(
            "{at}: packed graph of environment {} differs at f32 {} (node {} feature {}, or edge \
             {} past the features): cpu {:e} vs gpu {:e}",
            i / fs,
            i % fs,
            i % fs / socnav::sngnn::NODE_FEATURES,
            i % fs % socnav::sngnn::NODE_FEATURES,
            (i % fs).saturating_sub(socnav::sngnn::NODE_FEATURES * r.graphs.max_nodes),
            r.packed_f32[i],
            gf[i]
        );
    }
}

#[test]
fn exp1_sngnn_frames_and_graphs_match_the_cpu() {
    check("exp1_sngnn", 1.0, 40, false);
}

#[test]
fn exp2_sngnn_at_half_a_second_matches_the_cpu() {
    check("exp2_sngnn", 0.5, 40, true);
}

#[test]
fn exp3_sngnn_frames_and_graphs_match_the_cpu() {
    check("exp3_sngnn", 1.0, 40, true);
}

/// At dt = 0.1 s 0.1.1's f64 timestamps decide some frame gaps by rounding: the device's
/// per-tick gap table (`history::TickGaps`) must pick the CPU's frames from a 25-frame ring.
#[test]
fn exp1_sngnn_at_a_tenth_of_a_second_matches_the_cpu() {
    check("exp1_sngnn", 0.1, 60, false);
}

/// The gap table is data (`sn_gaps`), not shader text: an episode of 2^20 steps at dt = 0.1 s
/// (a table of 2^20 ticks) builds, and on the pipelines a short episode compiled.
#[test]
fn a_long_episode_takes_a_larger_gap_table_and_no_compile() {
    let Some(dev) = device() else {
        return;
    };
    let build = |length: u32| {
        let mut config = Config::from_name_or_path("exp1_sngnn").expect("exp1_sngnn");
        config.episode.time_step = 0.1;
        config.episode.length = length;
        let r = SngnnRollout::new(&config, 4, 1);
        GpuStages::with_sngnn_graphs(dev.clone(), &r.p, &r.s, &r.o, &["sngnn_graph"], r.graphs)
            .expect("the SNGNN pass")
    };
    drop(build(200));
    assert_eq!(
        build(1 << 20).pipelines_compiled(),
        0,
        "no pipeline compiled again"
    );
}
