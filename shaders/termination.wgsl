// requires: common/world.wgsl
//
// Twin of src/systems/termination.rs (stage `termination`, docs/spec.md 8.1): the episode's outcome
// in 0.1.1's priority order (out of map, goal reached, collision, timeout), exactly one outcome
// flag, COLLISION_WALL whenever the robot touches a wall; then the shadow robot's outcome (twin of
// `shadow_robot::shadow_outcome`); touching as `params.contact_shape` says (common/world.wgsl).
// Change both files in the same commit.

// Did the ORCA shadow robot collide or arrive at this step (it keeps its first outcome)?
fn shadow_outcome(e: u32) {
    if (su[batch.c_shadow_collided + e] != 0u || su[batch.c_shadow_reached + e] != 0u) {
        return;
    }
    let x = sf[batch.c_shadow_x + e];
    let y = sf[batch.c_shadow_y + e];
    let touch = world_touches(e, Disc(x, y, params.robot_radius));
    if (touch.human || touch.object) {
        su[batch.c_shadow_collided + e] = 1u;
    }
    let dx = sf[batch.c_goal_x + e] - x;
    let dy = sf[batch.c_goal_y + e] - y;
    if (sqrt(dx * dx + dy * dy) < params.robot_radius + params.goal_radius) {
        su[batch.c_shadow_reached + e] = 1u;
        su[batch.c_shadow_reach_tick + e] = su[batch.c_tick + e];
    }
}

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_termination(e: u32) {
    let x = sf[batch.c_robot_x + e];
    let y = sf[batch.c_robot_y + e];
    let out_of_map = abs(x) > 0.5 * sf[batch.c_map_x + e] || abs(y) > 0.5 * sf[batch.c_map_y + e];
    let dx = sf[batch.c_goal_x + e] - x;
    let dy = sf[batch.c_goal_y + e] - y;
    let success = sqrt(dx * dx + dy * dy) < params.robot_radius + params.goal_radius;
    let t = world_touches(e, Disc(x, y, params.robot_radius));
    let timeout = su[batch.c_tick + e] > params.episode_length;
    var flags = array<bool, 7>(false, false, false, false, false, false, false);
    if (out_of_map) {
        flags[INFO_OUT_OF_MAP] = true;
    } else if (success) {
        flags[INFO_SUCCESS] = true;
    } else if (t.human || t.object) {
        flags[INFO_COLLISION] = true;
        flags[INFO_COLLISION_HUMAN] = t.human;
        flags[INFO_COLLISION_OBJECT] = t.object;
    } else if (timeout) {
        flags[INFO_TIMEOUT] = true;
    }
    flags[INFO_COLLISION_WALL] = t.wall;
    let row = batch.co_info + e * batch.so_info;
    for (var k = 0u; k < 7u; k++) {
        outf[row + k] = select(0.0, 1.0, flags[k]);
    }
    let terminated = out_of_map || success || t.human || t.object;
    let truncated = !terminated && timeout;
    outu[batch.co_terminated + e] = select(0u, 1u, terminated);
    outu[batch.co_truncated + e] = select(0u, 1u, truncated);
    su[batch.c_done + e] = select(0u, 1u, terminated || truncated);
    shadow_outcome(e);
}
