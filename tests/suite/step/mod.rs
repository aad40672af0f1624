//! The stages of the step: one module per stage of `socnav::pipeline::STAGES`, named as the stage
//! (as are `src/systems/<stage>.rs` and `shaders/<stage>.wgsl`). A stage with both kinds of test
//! is a directory: `cpu` (and further CPU files where a stage has more) beside `gpu`; a stage with
//! one kind is a file. Five stages have only their GPU parity check (`begin_step`,
//! `group_velocities`, `group_motion`, `goals`, `formation`); their CPU side is checked through
//! whole steps (`whole_step/`, the golden replay).
//!
//! The hand-computed cases (docs/spec.md 4-6, 8; most `cpu` modules) run on exact scenes loaded
//! with `set_state` from small JSON documents written there (the format of `src/document.rs`), with
//! the helpers below and those of `tests/common/scene.rs`. Every expected value is worked out by
//! hand in the comments. Floats are compared with small tolerances because the simulator computes
//! in f32 (ulp 6e-8 at 1, 5e-7 at 5 m) with its own sin/cos/atan2 (`src/math.rs`); the tolerance at
//! each assert says what it covers.
//!
//! The CPU/GPU parity checks (`gpu` modules; docs/spec.md, determinism): from the same state,
//! parameters and actions, a stage's WGSL shader must leave the state and the outputs
//! bit-identical to its Rust twin on lavapipe (and on any adapter that rounds like it). States
//! come from real rollouts (random actions, resets and social events included); each stage then
//! runs many times on both sides, either chained (each side from its own last state) or from
//! states perturbed to reach the cases the stage decides between, and every column is compared
//! after every run (the harness: `tests/common/gpu.rs`). A perturbation may build on another
//! stage's: `reward`'s starts from `termination`'s, `autoreset`'s is `begin_step`'s.

use std::path::Path;

use socnav::spec::N_INFO;
use socnav::{Actions, BatchEnv, Config};

mod autoreset;
#[cfg(feature = "gpu")]
mod begin_step;
mod contacts;
#[cfg(feature = "gpu")]
mod formation;
#[cfg(feature = "gpu")]
mod goals;
#[cfg(feature = "gpu")]
mod group_motion;
#[cfg(feature = "gpu")]
mod group_velocities;
mod human_motion;
mod metrics;
mod observation;
mod reward;
mod robot_motion;
mod shadow_robot;
mod sngnn_graph;
mod sngnn_score;
mod social_events;
mod termination;

// ---------------------------------------------------------------------------------------------
// Scene documents
// ---------------------------------------------------------------------------------------------

/// Experiment 1 (10 m square room, dt = 1 s, robot r 0.25, humans r 0.36, plant r 0.4) with
/// room for the scenes of the hand-computed cases: up to 2 static and 2 walking humans, a
/// standing group of 2, a plant, a table and a free laptop.
fn scene_config() -> Config {
    let mut c =
        Config::from_file(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/exp1.toml")).unwrap();
    c.counts.static_humans = [0, 2];
    c.counts.dynamic_humans = [0, 2];
    c.counts.plants = [0, 1];
    c.counts.tables = [0, 1];
    c.counts.laptops = [0, 1];
    c.counts.standing_groups = [0, 1];
    c.counts.group_size = [2, 2];
    c
}

fn step(env: &mut BatchEnv, actions: &[[f32; 3]]) {
    let flat: Vec<f32> = actions.iter().flatten().copied().collect();
    env.step(Actions::Continuous(&flat)).unwrap();
}

fn info_of(env: &BatchEnv, e: usize, key: usize) -> f32 {
    env.outputs().info[e * N_INFO + key]
}

/// Robot pose (x, y, θ) and command (v_x, v_y, ω) of environment `e`.
fn robot(env: &BatchEnv, e: usize) -> ([f32; 3], [f32; 3]) {
    let s = env.state().unwrap();
    (
        [s.robot_x[e], s.robot_y[e], s.robot_theta[e]],
        [s.robot_vx[e], s.robot_vy[e], s.robot_w[e]],
    )
}

fn close(what: &str, got: f32, expected: f64, tol: f64) {
    assert!(
        (f64::from(got) - expected).abs() <= tol,
        "{what}: got {got}, expected {expected} (±{tol})"
    );
}

/// 0.1.1's scales of experiment 1: m/s and rad/s for an action of 1.
const V: f64 = 0.1;
const W: f64 = 0.387_596_899;
