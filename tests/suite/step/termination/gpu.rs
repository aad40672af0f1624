//! CPU/GPU parity of stage `termination` (docs/spec.md, determinism): from the same state,
//! parameters and actions, `shaders/termination.wgsl` must leave the state and the outputs
//! bit-identical to the Rust stage on lavapipe, on rolled-out states perturbed before each run (the
//! harness: `tests/common/gpu.rs`). [`scatter_robots`] is also the start of the perturbations of
//! `reward` and `metrics`.

use crate::common::gpu::*;
use socnav::StepParams;
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::spec::INFO_KEYS;
use socnav::state::BatchState;

/// Robots (and shadow robots) anywhere in and just outside the room, some at their goal, ticks
/// around the episode length, shadow outcomes cleared: every branch of `termination`.
pub(crate) fn scatter_robots(
    s: &mut BatchState,
    _: &mut Outputs,
    p: &StepParams,
    rng: &mut RngStream,
) {
    for e in 0..s.n_envs {
        let (hx, hy) = (0.6 * s.map_x[e], 0.6 * s.map_y[e]);
        s.robot_x[e] = uniform(rng, -hx, hx);
        s.robot_y[e] = uniform(rng, -hy, hy);
        s.shadow_x[e] = uniform(rng, -hx, hx);
        s.shadow_y[e] = uniform(rng, -hy, hy);
        if rng.next_f32() < 0.2 {
            s.goal_x[e] = s.robot_x[e] + uniform(rng, -0.6, 0.6);
            s.goal_y[e] = s.robot_y[e];
        }
        s.tick[e] = p.episode_length - 1 + (rng.next_u32() % 3);
        s.done[e] = 0;
        s.shadow_collided[e] = u32::from(rng.next_f32() < 0.1);
        s.shadow_reached[e] = 0;
    }
}

/// Contract: `termination` in every config kind (walls, plants, tables, laptops, groups): the
/// outcome flags, terminated/truncated, `done` and the shadow robot's outcome.
#[test]
fn termination() {
    for name in ["exp1", "exp2", "exp3", "lroom_mixed"] {
        let Some(raised) = check_parity("termination", config(name), 256, 20, Some(scatter_robots))
        else {
            return;
        };
        // Every outcome, collisions of each kind included, was decided on both sides.
        for (k, n) in raised.iter().enumerate() {
            assert!(*n > 0, "{name}: info flag {} never raised", INFO_KEYS[k]);
        }
    }
}
