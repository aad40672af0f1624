//! CPU/GPU parity of the ORCA stages `shadow_robot` and `group_velocities` (docs/spec.md,
//! determinism): their shaders (`shaders/shadow_robot.wgsl`, `shaders/group_velocities.wgsl`, over
//! `shaders/common/orca_world.wgsl` and `shaders/common/orca.wgsl`) must leave the state and the
//! outputs bit-identical to the Rust twins on lavapipe, from rolled-out states run many times,
//! chained and perturbed (shadow robots, lone humans and groups scattered, shadow outcomes
//! cleared so the shadows move), with neighbour velocities zero (0.1.1) and actual, diff-drive
//! and holonomic robots, and a time step other than 1 s. The harness: `tests/common/gpu.rs`.
//!
//! This module holds the harness of both, `shadow_robot`'s test and the test that the ORCA lists
//! are written before they are read (all three ORCA stages); `group_velocities`'s is in
//! `step/group_velocities.rs`, and the check of the shipped configs' capacities against the ORCA
//! list limits in `orca/gpu.rs`.

use crate::common;

use common::gpu::*;
use socnav::config::{Kinematics, OrcaNeighbourVelocity};
use socnav::math::PI;
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::state::BatchState;
use socnav::{Config, StepParams};

/// Runs per config (each chained on the last one's state and perturbed).
const RUNS: usize = 12;

/// About half of the environments get their shadow robot, lone humans and groups scattered over
/// the room (into each other and the obstacles too: collisions and LP3), random headings and
/// velocities, some goals exactly under the agent (zero preferred velocity); the shadow outcomes
/// are cleared (a tenth collided, to keep the early return) so that the shadows move.
fn scatter_agents(s: &mut BatchState, _: &mut Outputs, _: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        s.shadow_collided[e] = u32::from(rng.next_f32() < 0.1);
        s.shadow_reached[e] = 0;
        if rng.next_f32() < 0.5 {
            continue;
        }
        let (hx, hy) = (0.6 * s.map_x[e], 0.6 * s.map_y[e]);
        s.shadow_x[e] = uniform(rng, -hx, hx);
        s.shadow_y[e] = uniform(rng, -hy, hy);
        s.shadow_theta[e] = uniform(rng, -PI, PI);
        if rng.next_f32() < 0.05 {
            s.goal_x[e] = s.shadow_x[e];
            s.goal_y[e] = s.shadow_y[e];
        }
        let hb = e * s.strides.humans;
        for i in hb..hb + (s.n_static[e] + s.n_dynamic[e]) as usize {
            s.h_x[i] = uniform(rng, -hx, hx);
            s.h_y[i] = uniform(rng, -hy, hy);
            s.h_vx[i] = uniform(rng, -1.0, 1.0);
            s.h_vy[i] = uniform(rng, -1.0, 1.0);
        }
        let gb = e * s.strides.groups;
        for g in gb..gb + s.n_groups[e] as usize {
            s.g_x[g] = uniform(rng, -hx, hx);
            s.g_y[g] = uniform(rng, -hy, hy);
            s.g_vx[g] = uniform(rng, -0.5, 0.5);
            s.g_vy[g] = uniform(rng, -0.5, 0.5);
            if rng.next_f32() < 0.05 {
                s.g_goal_x[g] = s.g_x[g];
                s.g_goal_y[g] = s.g_y[g];
            }
        }
    }
}

/// `config` with neighbours at their actual velocities and a 0.3 s step.
pub(crate) fn actual(mut c: Config) -> Config {
    c.model.orca_neighbour_velocity = OrcaNeighbourVelocity::Actual;
    c.episode.time_step = 0.3;
    c
}

/// `config` with a holonomic robot and a 0.3 s step.
fn holonomic(mut c: Config) -> Config {
    c.robot.kinematics = Kinematics::Holonomic;
    c.episode.time_step = 0.3;
    c
}

/// `stage` on `c`: [`RUNS`] runs over 256 environments, chained and perturbed.
pub(crate) fn check(stage: &'static str, c: Config) {
    check_parity(stage, c, 256, RUNS, Some(scatter_agents));
}

/// Contract: `shadow_robot`: the shadow's ORCA velocity among the lone humans and moving groups
/// over the processed obstacles, its command (diff-drive and holonomic), its motion and path
/// length; arrived or collided shadows stay.
///
/// Each config is a new shader for llvmpipe to compile (tens of seconds each on a 2-core machine
/// without Mesa's shader cache, as in CI), so the variants are combined: 0.1.1's model on a room
/// with a plant, and everything else at once on the corridor room (tables, laptop users, groups).
#[test]
fn shadow_robot() {
    check("shadow_robot", config("exp1"));
    check("shadow_robot", holonomic(actual(config("corridor_mixed"))));
}

/// Issue 19: the backend's SPIR-V does not zero the ORCA lists (`backend::gpu::spirv`), so an
/// entry read before it is written would hold whatever the lane's memory held. With every entry
/// NaN and every index one no list holds at every clear (`GpuPaths::poison_orca_lists`), the
/// three ORCA stages stay bit-identical to the CPU from scattered agents (collisions, LP3,
/// goals under the agent), with neighbours at their actual velocities: no entry is read before
/// it is written. The three share one pipeline (the fused pass `motion`), compiled once more
/// for the poison.
#[test]
fn orca_lists_are_written_before_they_are_read() {
    let Some(mut dev) = device() else {
        return;
    };
    dev.paths.poison_orca_lists = true;
    for stage in ["shadow_robot", "group_velocities", "human_motion"] {
        check_parity_on(
            dev.clone(),
            stage,
            actual(config("exp2")),
            socnav::AutoresetMode::NextStep,
            256,
            RUNS,
            Some(scatter_agents),
        );
    }
}
