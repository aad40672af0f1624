// requires: common/orca_world.wgsl
//
// Twin of src/systems/group_velocities.rs (stage `group_velocities`, spec 4.4): every moving
// group is one ORCA super-agent (radius: member circle plus a human diameter, neighbour distance
// twice that) heading for the group goal at the human speed, in a simulator with the lone humans
// and the other moving groups (never the robot; groups see everything: `view: None`). All groups
// are solved from the positions at the start of the step; with `orca_actual_velocity` the
// others' velocities are read as the loop leaves them (groups before this one already updated),
// exactly as the Rust loop does. Same operations in the same order as the Rust file; change
// both in the same commit.
//
// If the ORCA lists overflow (common/orca_world.wgsl), the group's velocity becomes NaN.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= N_ENVS || su[C_STEPPING + e] == 0u) {
        return;
    }
    let gb = e * S_G_X;
    for (var g = gb; g < gb + su[C_N_GROUPS + e]; g++) {
        if (su[C_G_KIND + g] != GROUP_MOVING) {
            continue;
        }
        let x = sf[C_G_X + g];
        let y = sf[C_G_Y + g];
        let pref = orca_world_preferred(x, y, sf[C_G_GOAL_X + g], sf[C_G_GOAL_Y + g], params.human_max_speed);
        let radius = orca_world_group_agent_radius();
        var vel = vec2<f32>(0.0, 0.0);
        if (params.orca_actual_velocity != 0u) {
            vel = vec2<f32>(sf[C_G_VX + g], sf[C_G_VY + g]);
        }
        var agent = orca_world_agent(e, vec2<f32>(x, y), vel, pref, radius);
        agent.neighbor_dist = 2.0 * radius;
        let others = OrcaWorldOthers(ORCA_WORLD_NONE, g, false, perception_everything());
        let r = orca_world_velocity(e, agent, others);
        sf[C_G_VX + g] = r.velocity.x;
        sf[C_G_VY + g] = r.velocity.y;
    }
}
