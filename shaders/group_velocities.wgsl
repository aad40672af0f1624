// requires: common/orca_world.wgsl
//
// Twin of src/systems/group_velocities.rs (stage `group_velocities`, docs/spec.md 4.4): every
// moving group is one ORCA super-agent (radius: member circle plus a human diameter, neighbour
// distance twice that) heading for the group goal at the human speed, in a simulator with the lone
// humans and the other moving groups (never the robot; groups see everything: `view: None`). All
// groups are solved from the positions at the start of the step; with `orca_actual_velocity` the
// others' velocities are read as the loop leaves them (groups before this one already updated),
// exactly as the Rust loop does. Same operations in the same order as the Rust file; change
// both in the same commit.
//
// If the ORCA lists overflow (common/orca_world.wgsl), the group's velocity becomes NaN.

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_group_velocities(e: u32) {
    for (var g = at_group(e, 0u); g < at_group(e, su[batch.c_n_groups + e]); g += batch.k_group) {
        if (su[batch.c_g_kind + g] != GROUP_MOVING) {
            continue;
        }
        let x = sf[batch.c_g_x + g];
        let y = sf[batch.c_g_y + g];
        let pref = orca_world_preferred(x, y, sf[batch.c_g_goal_x + g], sf[batch.c_g_goal_y + g], params.human_max_speed);
        let radius = orca_world_group_agent_radius();
        var vel = vec2<f32>(0.0, 0.0);
        if (params.orca_actual_velocity != 0u) {
            vel = vec2<f32>(sf[batch.c_g_vx + g], sf[batch.c_g_vy + g]);
        }
        var agent = orca_world_agent(e, vec2<f32>(x, y), vel, pref, radius);
        agent.neighbor_dist = 2.0 * radius;
        let others = OrcaWorldOthers(ORCA_WORLD_NONE, g, false, perception_everything());
        let r = orca_world_velocity(e, agent, others);
        sf[batch.c_g_vx + g] = r.velocity.x;
        sf[batch.c_g_vy + g] = r.velocity.y;
    }
}
