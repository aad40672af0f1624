// requires: common/measures.wgsl
//
// Twin of src/systems/metrics.rs (stage `metrics`, docs/spec.md 8.2 and 8.3): every info metric of
// the step, the running accumulators behind them, and, when the episode ends, its statistics as the
// paper's table aggregates them. Change both files in the same commit. PERSONAL_SPACE (m,
// between the robot's surface and a human's centre) comes from the prelude (Rust
// `metrics::PERSONAL_SPACE`).

// The start of environment e's info row in `outf`.
fn info_row(e: u32) -> u32 {
    return batch.co_info + e * batch.so_info;
}

// FAILURE_TO_PROGRESS, STALLED_TIME, TIME_TO_REACH_GOAL, PATH_LENGTH.
fn progress(e: u32) {
    let row = info_row(e);
    let dx = sf[batch.c_goal_x + e] - sf[batch.c_robot_x + e];
    let dy = sf[batch.c_goal_y + e] - sf[batch.c_robot_y + e];
    let d = sqrt(dx * dx + dy * dy);
    if (d > sf[batch.c_m_prev_goal_dist + e]) {
        su[batch.c_m_failure_to_progress + e] += 1u;
    }
    sf[batch.c_m_prev_goal_dist + e] = d;
    let v = speed(sf[batch.c_robot_vx + e], sf[batch.c_robot_vy + e]);
    if (v == 0.0) {
        sf[batch.c_m_stalled_time + e] += params.dt;
    }
    sf[batch.c_m_path_length + e] += params.dt * v;
    outf[row + INFO_FAILURE_TO_PROGRESS] = f32(su[batch.c_m_failure_to_progress + e]);
    outf[row + INFO_STALLED_TIME] = sf[batch.c_m_stalled_time + e];
    if (outf[row + INFO_SUCCESS] != 0.0) {
        outf[row + INFO_TIME_TO_REACH_GOAL] = f32(su[batch.c_tick + e]) * params.dt;
    } else {
        outf[row + INFO_TIME_TO_REACH_GOAL] = math_nan();
    }
    outf[row + INFO_PATH_LENGTH] = sf[batch.c_m_path_length + e];
}

// Running min / mean / max over the episode's `tick` steps of the column triple starting at the
// offsets given (min, avg, max columns of one environment).
fn running(min_at: u32, avg_at: u32, max_at: u32, value: f32, tick: f32) {
    sf[min_at] = min(sf[min_at], value);
    sf[max_at] = max(sf[max_at], value);
    sf[avg_at] = (sf[avg_at] * (tick - 1.0) + value) / tick;
}

// V, A and JERK statistics of the robot-frame linear command.
fn motion_statistics(e: u32, tick: f32) {
    let vx = sf[batch.c_robot_vx + e];
    let vy = sf[batch.c_robot_vy + e];
    let a = command_acceleration(e);
    let jx = (a.x - sf[batch.c_m_prev_ax + e]) / params.dt;
    let jy = (a.y - sf[batch.c_m_prev_ay + e]) / params.dt;
    running(batch.c_m_v_min + e, batch.c_m_v_avg + e, batch.c_m_v_max + e, speed(vx, vy), tick);
    running(batch.c_m_a_min + e, batch.c_m_a_avg + e, batch.c_m_a_max + e, speed(a.x, a.y), tick);
    running(batch.c_m_j_min + e, batch.c_m_j_avg + e, batch.c_m_j_max + e, speed(jx, jy), tick);
    sf[batch.c_m_prev_vx + e] = vx;
    sf[batch.c_m_prev_vy + e] = vy;
    sf[batch.c_m_prev_ax + e] = a.x;
    sf[batch.c_m_prev_ay + e] = a.y;
    let row = info_row(e);
    outf[row + INFO_V_MIN] = sf[batch.c_m_v_min + e];
    outf[row + INFO_V_AVG] = sf[batch.c_m_v_avg + e];
    outf[row + INFO_V_MAX] = sf[batch.c_m_v_max + e];
    outf[row + INFO_A_MIN] = sf[batch.c_m_a_min + e];
    outf[row + INFO_A_AVG] = sf[batch.c_m_a_avg + e];
    outf[row + INFO_A_MAX] = sf[batch.c_m_a_max + e];
    outf[row + INFO_JERK_MIN] = sf[batch.c_m_j_min + e];
    outf[row + INFO_JERK_AVG] = sf[batch.c_m_j_avg + e];
    outf[row + INFO_JERK_MAX] = sf[batch.c_m_j_max + e];
}

// Steps until the robot and a human touch at constant velocities, the smallest over the humans;
// 0 when already touching, -1 when none approaches (docs/spec.md 8.2).
fn time_to_collision(e: u32) -> f32 {
    let vrx = sf[batch.c_robot_wvx + e];
    let vry = sf[batch.c_robot_wvy + e];
    let rx = sf[batch.c_robot_x + e];
    let ry = sf[batch.c_robot_y + e];
    let reach = params.robot_radius + params.human_radius;
    var best = math_inf();
    for (var i = at_human(e, 0u); i < at_human(e, su[batch.c_n_humans + e]); i += batch.k_human) {
        let vhx = sf[batch.c_h_vx + i];
        let vhy = sf[batch.c_h_vy + i];
        let px = rx - sf[batch.c_h_x + i];
        let py = ry - sf[batch.c_h_y + i];
        let dist = speed(px, py);
        var t = 0.0;
        if (dist > reach) {
            let vx = vhx - vrx;
            let vy = vhy - vry;
            let approach = (vx * px + vy * py) / dist;
            if (approach <= 0.0) {
                continue;
            }
            let tc = dist / approach;
            let gx = (sf[batch.c_h_x + i] + vhx * tc) - (rx + vrx * tc);
            let gy = (sf[batch.c_h_y + i] + vhy * tc) - (ry + vry * tc);
            if (speed(gx, gy) > reach) {
                continue;
            }
            t = ceil(tc / params.dt);
        }
        best = min(best, t);
    }
    if (best < math_inf()) {
        return best;
    }
    return -1.0;
}

// STL and SPL: 0 unless this step succeeded; then 1 when the shadow robot collided or has not
// arrived yet, else the ratio of its time (path length) to the robot's, at most 1.
fn shadow_ratios(e: u32) {
    let row = info_row(e);
    var stl = 0.0;
    var spl = 0.0;
    if (outf[row + INFO_SUCCESS] == 0.0) {
        stl = 0.0;
        spl = 0.0;
    } else if (su[batch.c_shadow_collided + e] != 0u || su[batch.c_shadow_reached + e] == 0u) {
        stl = 1.0;
        spl = 1.0;
    } else {
        stl = min(f32(su[batch.c_shadow_reach_tick + e]) / f32(su[batch.c_tick + e]), 1.0);
        spl = min(sf[batch.c_shadow_path_length + e] / sf[batch.c_m_path_length + e], 1.0);
    }
    outf[row + INFO_STL] = stl;
    outf[row + INFO_SPL] = spl;
}

// Per-episode sums and minima over the steps (docs/spec.md 8.3).
fn accumulate_episode(e: u32, reward: f32) {
    let row = info_row(e);
    sf[batch.c_ep_return + e] += reward;
    sf[batch.c_ep_min_human_dist + e] = min(sf[batch.c_ep_min_human_dist + e], outf[row + INFO_MINIMUM_DISTANCE_TO_HUMAN]);
    sf[batch.c_ep_min_obstacle_dist + e] = min(sf[batch.c_ep_min_obstacle_dist + e], outf[row + INFO_MINIMUM_OBSTACLE_DISTANCE]);
    let avg = outf[row + INFO_AVERAGE_OBSTACLE_DISTANCE];
    if (!math_is_nan_bits(avg)) {
        sf[batch.c_ep_sum_avg_obstacle_dist + e] += avg;
    }
    let ttc = outf[row + INFO_TIME_TO_COLLISION];
    if (ttc < 0.0) {
        sf[batch.c_ep_sum_ttc + e] += f32(params.episode_length);
    } else {
        sf[batch.c_ep_sum_ttc + e] += ttc;
    }
    sf[batch.c_ep_sum_discomfort_dsrnn + e] += outf[row + INFO_DISCOMFORT_DSRNN];
    sf[batch.c_ep_sum_sngnn + e] += outf[row + INFO_SNGNN_REWARD];
}

// The statistics of the episode that just ended (order of the Rust EPISODE_KEYS).
fn write_episode(e: u32) {
    let row = info_row(e);
    let out = batch.co_episode + e * batch.so_episode;
    let length = f32(su[batch.c_tick + e]);
    let success = outf[row + INFO_SUCCESS];
    let collision = outf[row + INFO_COLLISION];
    outf[out + EP_FAILURE_TO_PROGRESS] = outf[row + INFO_FAILURE_TO_PROGRESS];
    outf[out + EP_STALLED_TIME] = outf[row + INFO_STALLED_TIME];
    outf[out + EP_PATH_LENGTH] = outf[row + INFO_PATH_LENGTH];
    outf[out + EP_V_MIN] = outf[row + INFO_V_MIN];
    outf[out + EP_V_AVG] = outf[row + INFO_V_AVG];
    outf[out + EP_V_MAX] = outf[row + INFO_V_MAX];
    outf[out + EP_A_MIN] = outf[row + INFO_A_MIN];
    outf[out + EP_A_AVG] = outf[row + INFO_A_AVG];
    outf[out + EP_A_MAX] = outf[row + INFO_A_MAX];
    outf[out + EP_JERK_MIN] = outf[row + INFO_JERK_MIN];
    outf[out + EP_JERK_AVG] = outf[row + INFO_JERK_AVG];
    outf[out + EP_JERK_MAX] = outf[row + INFO_JERK_MAX];
    outf[out + EP_PERSONAL_SPACE_COMPLIANCE] = outf[row + INFO_PERSONAL_SPACE_COMPLIANCE];
    outf[out + EP_STL] = outf[row + INFO_STL];
    outf[out + EP_SPL] = outf[row + INFO_SPL];
    outf[out + EP_RETURN] = sf[batch.c_ep_return + e];
    outf[out + EP_LENGTH] = length;
    outf[out + EP_SUCCESS] = success;
    outf[out + EP_COLLISION] = collision;
    outf[out + EP_COLLISION_HUMAN] = outf[row + INFO_COLLISION_HUMAN];
    outf[out + EP_COLLISION_OBJECT] = outf[row + INFO_COLLISION_OBJECT];
    outf[out + EP_COLLISION_WALL] = outf[row + INFO_COLLISION_WALL];
    outf[out + EP_TIMEOUT] = outf[row + INFO_TIMEOUT];
    outf[out + EP_OUT_OF_MAP] = outf[row + INFO_OUT_OF_MAP];
    if (collision != 0.0) {
        outf[out + EP_TIME_TAKEN] = f32(params.episode_length);
    } else {
        outf[out + EP_TIME_TAKEN] = length;
    }
    if (success != 0.0) {
        outf[out + EP_TIME_TO_REACH_GOAL] = outf[row + INFO_TIME_TO_REACH_GOAL];
    } else {
        outf[out + EP_TIME_TO_REACH_GOAL] = f32(params.episode_length);
    }
    outf[out + EP_MINIMUM_DISTANCE_TO_HUMAN] = sf[batch.c_ep_min_human_dist + e];
    outf[out + EP_MINIMUM_OBSTACLE_DISTANCE] = sf[batch.c_ep_min_obstacle_dist + e];
    outf[out + EP_AVERAGE_OBSTACLE_DISTANCE] = sf[batch.c_ep_sum_avg_obstacle_dist + e] / length;
    outf[out + EP_TIME_TO_COLLISION] = sf[batch.c_ep_sum_ttc + e] / length;
    outf[out + EP_DISCOMFORT_DSRNN] = sf[batch.c_ep_sum_discomfort_dsrnn + e];
    outf[out + EP_DISCOMFORT_SNGNN] = sf[batch.c_ep_sum_sngnn + e];
}

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_metrics(e: u32) {
    let row = info_row(e);
    let tick = f32(su[batch.c_tick + e]);
    progress(e);
    motion_statistics(e, tick);
    let min_human = min_human_distance(e);
    outf[row + INFO_MINIMUM_DISTANCE_TO_HUMAN] = min_human;
    if (min_human - params.robot_radius >= PERSONAL_SPACE) {
        su[batch.c_m_compliant + e] += 1u;
    }
    outf[row + INFO_PERSONAL_SPACE_COMPLIANCE] = f32(su[batch.c_m_compliant + e]) / tick;
    outf[row + INFO_TIME_TO_COLLISION] = time_to_collision(e);
    let obstacles = obstacle_distances(e);
    outf[row + INFO_MINIMUM_OBSTACLE_DISTANCE] = obstacles.x;
    outf[row + INFO_AVERAGE_OBSTACLE_DISTANCE] = obstacles.y;
    shadow_ratios(e);
    accumulate_episode(e, outf[batch.co_reward + e]);
    if (su[batch.c_done + e] != 0u) {
        write_episode(e);
        outu[batch.co_episode_done + e] = 1u;
        outu[batch.co_episode_seed_lo + e] = su[batch.c_seed_lo + e];
        outu[batch.co_episode_seed_hi + e] = su[batch.c_seed_hi + e];
    }
}
