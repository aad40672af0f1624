//! CPU/GPU parity of stage `metrics` (docs/spec.md, determinism): from the same state, parameters
//! and actions, `shaders/metrics.wgsl` must leave the state and the outputs bit-identical to the
//! Rust stage on lavapipe, on rolled-out states perturbed before each run (the harness:
//! `tests/common/gpu.rs`).

use crate::common::gpu::*;
use crate::step::reward::gpu::scatter_for_reward;
use socnav::StepParams;
use socnav::config::Kinematics;
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::state::BatchState;

/// As for `reward`, plus a random reward, episodes ending for a third of the robots, and shadow
/// robots arrived at random ticks: every metric and the episode statistics of `metrics`.
fn scatter_for_metrics(s: &mut BatchState, o: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    scatter_for_reward(s, o, p, rng);
    for e in 0..s.n_envs {
        o.reward[e] = uniform(rng, -1.0, 1.0);
        s.done[e] = u32::from(rng.next_f32() < 0.3);
        s.shadow_reached[e] = u32::from(rng.next_f32() < 0.5);
        s.shadow_reach_tick[e] = 1 + rng.next_u32() % s.tick[e];
        s.shadow_path_length[e] = uniform(rng, 0.0, 20.0);
        s.m_path_length[e] = uniform(rng, 0.0, 20.0);
        s.robot_vy[e] = if p.holonomic != 0 {
            uniform(rng, -0.1, 0.1)
        } else {
            0.0
        };
    }
}

/// Contract: `metrics`: the info metrics, their running accumulators, and the statistics of the
/// episodes that end (time to collision, obstacle distances, STL/SPL included).
#[test]
fn metrics() {
    for name in ["exp1", "exp2", "exp3", "lroom_mixed"] {
        check_parity("metrics", config(name), 256, 20, Some(scatter_for_metrics));
    }
    let mut c = config("exp2");
    c.robot.kinematics = Kinematics::Holonomic;
    c.episode.time_step = 0.3;
    check_parity("metrics", c, 256, 20, Some(scatter_for_metrics));
}
