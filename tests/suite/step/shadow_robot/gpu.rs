//! CPU/GPU parity of the ORCA stages `shadow_robot` and `group_velocities` (DESIGN.md section 4):
//! their shaders (`shaders/shadow_robot.wgsl`, `shaders/group_velocities.wgsl`, over
//! `shaders/common/orca_world.wgsl` and `shaders/common/orca.wgsl`) must leave the state and the
//! outputs bit-identical to the Rust twins on lavapipe, from rolled-out states run many times,
//! chained and perturbed (shadow robots, lone humans and groups scattered, shadow outcomes
//! cleared so the shadows move), with neighbour velocities zero (0.1.1) and actual, diff-drive
//! and holonomic robots, and a time step other than 1 s. The harness: `tests/common/gpu.rs`.

use crate::common;

use common::gpu::*;
use socnav::config::{Kinematics, OrcaNeighbourVelocity};
use socnav::math::PI;
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::state::{BatchState, Caps};
use socnav::{Config, StepParams};

/// The shipped configs whose capacities are checked against the ORCA list limits.
const CONFIGS: [&str; 5] = ["exp1", "exp2", "exp3", "lroom_mixed", "corridor_mixed"];

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
fn actual(mut c: Config) -> Config {
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

/// Contract: the capacities of every shipped config keep the agent neighbour list of
/// `common/orca_world.wgsl` within its limit (every human and group plus the robot fit), so it
/// never overflows. The obstacle neighbour list is bounded by the edges within the obstacle range
/// of one agent, not by the capacities: where the vertex capacity exceeds its limit (the configs
/// listed here) an overflow is possible in principle, and the shaders would then write NaN (a
/// loud difference from the CPU, never a silent one).
#[test]
fn shipped_capacities_fit_the_orca_lists() {
    const ORCA_MAX_AGENT_NEIGHBORS: usize = 64;
    const ORCA_MAX_OBSTACLE_NEIGHBORS: usize = 128;
    let src = socnav::backend::wgsl::source("common/orca.wgsl").expect("embedded");
    assert!(src.contains("const ORCA_MAX_AGENT_NEIGHBORS: u32 = 64u;"));
    assert!(src.contains("const ORCA_MAX_OBSTACLE_NEIGHBORS: u32 = 128u;"));
    let mut unbounded = Vec::new();
    for name in CONFIGS.iter().chain(&["stress"]) {
        let caps = Caps::from_config(&config(name));
        println!("{name}: {caps:?}");
        assert!(
            caps.humans + caps.groups < ORCA_MAX_AGENT_NEIGHBORS,
            "{name}: {caps:?}"
        );
        if caps.obstacle_vertices > ORCA_MAX_OBSTACLE_NEIGHBORS {
            unbounded.push(*name);
        }
    }
    assert_eq!(unbounded, OBSTACLE_LIST_NOT_BOUNDED_BY_CAPS);
}

/// The shipped configs whose obstacle vertex capacity exceeds ORCA_MAX_OBSTACLE_NEIGHBORS.
const OBSTACLE_LIST_NOT_BOUNDED_BY_CAPS: &[&str] = &["lroom_mixed", "corridor_mixed", "stress"];

/// `stage` on `c`: [`RUNS`] runs over 256 environments, chained and perturbed.
fn check(stage: &'static str, c: Config) {
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

/// Contract: `group_velocities`: each moving group's ORCA velocity as a super-agent among the
/// lone humans and the other moving groups, in group order (with actual velocities, earlier
/// groups' new ones).
///
/// Two shaders to compile (see `shadow_robot`): 0.1.1's model with experiment 2's groups, and
/// actual neighbour velocities at dt = 0.3 s in the L room.
#[test]
fn group_velocities() {
    check("group_velocities", config("exp2"));
    check("group_velocities", actual(config("lroom_mixed")));
}
