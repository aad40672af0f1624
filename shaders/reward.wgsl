// requires: common/measures.wgsl
//
// Twin of src/systems/reward.rs (stage `reward`, docs/spec.md 6.2 and 6.3): the DSRNN-style reward
// or SNGNN-v2's. Terminal steps get the outcome's constant; other steps the distance, discomfort
// and alive terms plus the weighted terms beyond 0.1.1 (skipped at weight 0). The reward's info
// values persist: a terminal step reports those of the previous step. Change both files in the
// same commit.
//
// SNGNN-v2's score comes from the passes before this one (`sngnn_graph`, then the network,
// `GpuStages::attach_sngnn_net`): for every environment this stage scores, they leave the room
// node's first output in `r_discomfort_sngnn`, which is clamped here as the CPU clamps it.
//
// The prelude defines REWARD_SNGNN (`StepParams::reward_kind` of the SNGNN-v2 reward) and
// SNGNN_WEIGHT (0.1.1's weight of its term) from the Rust constants.

// The robot's world-frame velocity (m/s), computed with the motion (Rust
// `robot_motion::robot_world_velocity`).
fn robot_world_velocity(e: u32) -> vec2<f32> {
    return vec2<f32>(sf[batch.c_robot_wvx + e], sf[batch.c_robot_wvy + e]);
}

// Clearance (m) over the next dt between the robot and a human at (x, y) moving at (hvx, hvy).
fn clearance(e: u32, x: f32, y: f32, hvx: f32, hvy: f32) -> f32 {
    let vr = robot_world_velocity(e);
    let px = x - sf[batch.c_robot_x + e];
    let py = y - sf[batch.c_robot_y + e];
    let vx = hvx - vr.x;
    let vy = hvy - vr.y;
    return geo_origin_segment_distance(px, py, vx * params.dt, vy * params.dt)
        - params.human_radius
        - params.robot_radius;
}

// The smallest predicted clearance (m) between the robot and any human; +inf without humans.
fn min_predicted_clearance(e: u32) -> f32 {
    var d_min = math_inf();
    for (var i = at_human(e, 0u); i < at_human(e, su[batch.c_n_humans + e]); i += batch.k_human) {
        d_min = min(d_min, clearance(e, sf[batch.c_h_x + i], sf[batch.c_h_y + i], sf[batch.c_h_vx + i], sf[batch.c_h_vy + i]));
    }
    if (params.dsrnn_pseudo_humans != 0u) {
        for (var g = at_group(e, 0u); g < at_group(e, su[batch.c_n_groups + e]); g += batch.k_group) {
            let first_slot = su[batch.c_g_first + g];
            let first = at_human(e, first_slot);
            let n = su[batch.c_g_count + g];
            var total = 0.0;
            for (var k = first; k < at_human(e, first_slot + n); k += batch.k_human) {
                total += sf[batch.c_h_speed + k];
            }
            let mean_speed = total / f32(n);
            let sc = math_sin_cos(sf[batch.c_h_theta + first]);
            d_min = min(d_min, clearance(e, sf[batch.c_g_x + g], sf[batch.c_g_y + g], mean_speed * sc.y, mean_speed * sc.x));
        }
        for (var u = at_laptop_user(e, 0u); u < at_laptop_user(e, su[batch.c_n_laptop_users + e]); u += batch.k_laptop_user) {
            let h = at_human(e, su[batch.c_lu_human + u]);
            let l = at_laptop(e, su[batch.c_lu_laptop + u]);
            let cx = 0.5 * (sf[batch.c_h_x + h] + sf[batch.c_l_x + l]);
            let cy = 0.5 * (sf[batch.c_h_y + h] + sf[batch.c_l_y + l]);
            d_min = min(d_min, clearance(e, cx, cy, 0.0, 0.0));
        }
    }
    return d_min;
}

// r plus the weighted terms beyond 0.1.1; a term with weight 0 is not evaluated at all.
fn with_extra_terms(e: u32, r0: f32) -> f32 {
    var r = r0;
    if (params.reward_personal_space_weight != 0.0) {
        let c = min_human_distance(e) - params.robot_radius;
        let intrusion = max(params.reward_personal_space_distance - c, 0.0);
        r += params.reward_personal_space_weight * intrusion;
    }
    if (params.reward_obstacle_weight != 0.0) {
        let c = obstacle_distances(e).x - params.robot_radius;
        let intrusion = max(params.reward_obstacle_distance - c, 0.0);
        r += params.reward_obstacle_weight * intrusion;
    }
    if (params.reward_stalled_weight != 0.0 && speed(sf[batch.c_robot_vx + e], sf[batch.c_robot_vy + e]) == 0.0) {
        r += params.reward_stalled_weight;
    }
    if (params.reward_acceleration_weight != 0.0) {
        let a = command_acceleration(e);
        r += params.reward_acceleration_weight * speed(a.x, a.y);
    }
    return r;
}

// The reward of a non-terminal step; updates the reward memory.
fn step_reward(e: u32) -> f32 {
    let dx = sf[batch.c_goal_x + e] - sf[batch.c_robot_x + e];
    let dy = sf[batch.c_goal_y + e] - sf[batch.c_robot_y + e];
    let d = sqrt(dx * dx + dy * dy);
    var r_dist = 0.0;
    if (su[batch.c_r_has_prev + e] != 0u) {
        r_dist = -(params.reward_distance_scale * (d - sf[batch.c_r_prev_dist + e]));
    }
    let d_min = min_predicted_clearance(e);
    var r_disc = 0.0;
    if (d_min < params.reward_discomfort_distance) {
        r_disc = (d_min - params.reward_discomfort_distance) * params.reward_discomfort_factor * params.dt;
    }
    sf[batch.c_r_prev_dist + e] = d;
    su[batch.c_r_has_prev + e] = 1u;
    sf[batch.c_r_distance + e] = r_dist;
    sf[batch.c_r_discomfort_dsrnn + e] = r_disc;
    sf[batch.c_r_alive + e] = params.reward_alive;
    var r: f32;
    if (params.reward_kind == REWARD_SNGNN) {
        let discomfort = clamp_unit(sf[batch.c_r_discomfort_sngnn + e]);
        sf[batch.c_r_discomfort_sngnn + e] = discomfort;
        sf[batch.c_r_sngnn + e] = discomfort - 1.0;
        // docs/spec.md 6.3: the DSRNN discomfort is computed for the info only.
        r = (discomfort - 1.0) * SNGNN_WEIGHT + r_dist + params.reward_alive;
    } else {
        sf[batch.c_r_discomfort_sngnn + e] = 0.0;
        r = r_disc + r_dist + params.reward_alive;
    }
    return with_extra_terms(e, r);
}

// Rust's `x.clamp(0.0, 1.0)`, comparisons written out: WGSL's clamp may return either zero for
// -0.0.
fn clamp_unit(x: f32) -> f32 {
    if (x < 0.0) {
        return 0.0;
    }
    if (x > 1.0) {
        return 1.0;
    }
    return x;
}

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_reward(e: u32) {
    let row = batch.co_info + e * batch.so_info;
    var r: f32;
    if (outf[row + INFO_OUT_OF_MAP] != 0.0) {
        r = params.reward_out_of_map;
    } else if (outf[row + INFO_SUCCESS] != 0.0) {
        r = params.reward_reach;
    } else if (outf[row + INFO_COLLISION] != 0.0) {
        r = params.reward_collision;
    } else if (outf[row + INFO_TIMEOUT] != 0.0) {
        r = params.reward_timeout;
    } else {
        r = step_reward(e);
    }
    outf[batch.co_reward + e] = r;
    outf[row + INFO_DISCOMFORT_SNGNN] = sf[batch.c_r_discomfort_sngnn + e];
    outf[row + INFO_DISCOMFORT_DSRNN] = sf[batch.c_r_discomfort_dsrnn + e];
    outf[row + INFO_DISTANCE_REWARD] = sf[batch.c_r_distance + e];
    outf[row + INFO_ALIVE_REWARD] = sf[batch.c_r_alive + e];
    outf[row + INFO_SNGNN_REWARD] = sf[batch.c_r_sngnn + e];
}
