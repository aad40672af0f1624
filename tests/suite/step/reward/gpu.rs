//! CPU/GPU parity of stage `reward` (docs/spec.md, determinism): from the same state, parameters
//! and actions, `shaders/reward.wgsl` must leave the state and the outputs bit-identical to the
//! Rust stage on lavapipe, on rolled-out states perturbed before each run (the harness:
//! `tests/common/gpu.rs`). [`scatter_for_reward`] is also the start of the perturbation of
//! `metrics`.

use crate::common::gpu::*;
use crate::step::termination::gpu::scatter_robots;
use socnav::StepParams;
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::spec::N_INFO;
use socnav::state::BatchState;

/// Robots scattered as for `termination`, moving at random world velocities and commands, with
/// random previous goal distances (or none) and an outcome drawn for a quarter of them: every
/// branch and term of `reward`.
pub(crate) fn scatter_for_reward(
    s: &mut BatchState,
    o: &mut Outputs,
    p: &StepParams,
    rng: &mut RngStream,
) {
    scatter_robots(s, o, p, rng);
    for e in 0..s.n_envs {
        s.robot_wvx[e] = uniform(rng, -0.2, 0.2);
        s.robot_wvy[e] = uniform(rng, -0.2, 0.2);
        let stalled = rng.next_f32() < 0.2;
        s.robot_vx[e] = if stalled {
            0.0
        } else {
            uniform(rng, -0.1, 0.1)
        };
        s.m_prev_vx[e] = uniform(rng, -0.1, 0.1);
        s.r_has_prev[e] = u32::from(rng.next_f32() < 0.8);
        s.r_prev_dist[e] = uniform(rng, 0.0, 10.0);
        let row = &mut o.info[e * N_INFO..e * N_INFO + 7];
        row.fill(0.0);
        if rng.next_f32() < 0.25 {
            row[(rng.next_u32() % 7) as usize] = 1.0;
        }
    }
}

/// Contract: `reward`: terminal constants, distance and discomfort terms (pseudo-humans of
/// groups and laptop users included), the persisting info values, and the weighted terms.
#[test]
fn reward() {
    for name in ["exp1", "exp2", "exp3"] {
        check_parity("reward", config(name), 256, 20, Some(scatter_for_reward));
    }
    let mut c = config("exp2");
    c.reward.personal_space_weight = -1.0;
    c.reward.personal_space_distance = 2.0;
    c.reward.obstacle_weight = -0.5;
    c.reward.obstacle_distance = 1.0;
    c.reward.stalled_weight = -0.1;
    c.reward.acceleration_weight = -0.3;
    c.episode.time_step = 0.3;
    check_parity("reward", c, 256, 20, Some(scatter_for_reward));
}
