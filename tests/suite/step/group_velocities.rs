//! CPU/GPU parity of stage `group_velocities` (`src/systems/group_velocities.rs`,
//! `shaders/group_velocities.wgsl`; docs/spec.md, determinism), with the harness of the ORCA stages
//! (`step/shadow_robot/gpu.rs`: rolled-out states, chained and perturbed runs).

use crate::common::gpu::config;
use crate::step::shadow_robot::gpu::{actual, check};

/// Contract: `group_velocities`: each moving group's ORCA velocity as a super-agent among the
/// lone humans and the other moving groups, in group order (with actual velocities, earlier
/// groups' new ones).
///
/// Two shaders to compile (see `shadow_robot` in `step/shadow_robot/gpu.rs`): 0.1.1's model
/// with experiment 2's groups, and actual neighbour velocities at dt = 0.3 s in the L room.
#[test]
fn group_velocities() {
    check("group_velocities", config("exp2"));
    check("group_velocities", actual(config("lroom_mixed")));
}
