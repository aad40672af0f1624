// requires: common/measures.wgsl
//
// Twin of src/systems/metrics.rs (stage `metrics`, spec 8.2 and 8.3): every info metric of the
// step, the running accumulators behind them, and, when the episode ends, its statistics as the
// paper's table aggregates them. Change both files in the same commit.

// Personal-space threshold (m) between the robot's surface and a human's centre (0.45, exactly
// the f32 of the Rust constant).
const PERSONAL_SPACE: f32 = 0x1.ccccccp-2f;

// The start of environment e's info row in `outf`.
fn info_row(e: u32) -> u32 {
    return CO_INFO + e * SO_INFO;
}

// FAILURE_TO_PROGRESS, STALLED_TIME, TIME_TO_REACH_GOAL, PATH_LENGTH.
fn progress(e: u32) {
    let row = info_row(e);
    let dx = sf[C_GOAL_X + e] - sf[C_ROBOT_X + e];
    let dy = sf[C_GOAL_Y + e] - sf[C_ROBOT_Y + e];
    let d = sqrt(dx * dx + dy * dy);
    if (d > sf[C_M_PREV_GOAL_DIST + e]) {
        su[C_M_FAILURE_TO_PROGRESS + e] += 1u;
    }
    sf[C_M_PREV_GOAL_DIST + e] = d;
    let v = speed(sf[C_ROBOT_VX + e], sf[C_ROBOT_VY + e]);
    if (v == 0.0) {
        sf[C_M_STALLED_TIME + e] += params.dt;
    }
    sf[C_M_PATH_LENGTH + e] += params.dt * v;
    outf[row + INFO_FAILURE_TO_PROGRESS] = f32(su[C_M_FAILURE_TO_PROGRESS + e]);
    outf[row + INFO_STALLED_TIME] = sf[C_M_STALLED_TIME + e];
    if (outf[row + INFO_SUCCESS] != 0.0) {
        outf[row + INFO_TIME_TO_REACH_GOAL] = f32(su[C_TICK + e]) * params.dt;
    } else {
        outf[row + INFO_TIME_TO_REACH_GOAL] = math_nan();
    }
    outf[row + INFO_PATH_LENGTH] = sf[C_M_PATH_LENGTH + e];
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
    let vx = sf[C_ROBOT_VX + e];
    let vy = sf[C_ROBOT_VY + e];
    let a = command_acceleration(e);
    let jx = (a.x - sf[C_M_PREV_AX + e]) / params.dt;
    let jy = (a.y - sf[C_M_PREV_AY + e]) / params.dt;
    running(C_M_V_MIN + e, C_M_V_AVG + e, C_M_V_MAX + e, speed(vx, vy), tick);
    running(C_M_A_MIN + e, C_M_A_AVG + e, C_M_A_MAX + e, speed(a.x, a.y), tick);
    running(C_M_J_MIN + e, C_M_J_AVG + e, C_M_J_MAX + e, speed(jx, jy), tick);
    sf[C_M_PREV_VX + e] = vx;
    sf[C_M_PREV_VY + e] = vy;
    sf[C_M_PREV_AX + e] = a.x;
    sf[C_M_PREV_AY + e] = a.y;
    let row = info_row(e);
    outf[row + INFO_V_MIN] = sf[C_M_V_MIN + e];
    outf[row + INFO_V_AVG] = sf[C_M_V_AVG + e];
    outf[row + INFO_V_MAX] = sf[C_M_V_MAX + e];
    outf[row + INFO_A_MIN] = sf[C_M_A_MIN + e];
    outf[row + INFO_A_AVG] = sf[C_M_A_AVG + e];
    outf[row + INFO_A_MAX] = sf[C_M_A_MAX + e];
    outf[row + INFO_JERK_MIN] = sf[C_M_J_MIN + e];
    outf[row + INFO_JERK_AVG] = sf[C_M_J_AVG + e];
    outf[row + INFO_JERK_MAX] = sf[C_M_J_MAX + e];
}

// Steps until the robot and a human touch at constant velocities, the smallest over the humans;
// 0 when already touching, -1 when none approaches (spec 8.2).
fn time_to_collision(e: u32) -> f32 {
    let vrx = sf[C_ROBOT_WVX + e];
    let vry = sf[C_ROBOT_WVY + e];
    let rx = sf[C_ROBOT_X + e];
    let ry = sf[C_ROBOT_Y + e];
    let reach = params.robot_radius + params.human_radius;
    let hb = e * S_H_X;
    var best = math_inf();
    for (var i = hb; i < hb + su[C_N_HUMANS + e]; i++) {
        let vhx = sf[C_H_VX + i];
        let vhy = sf[C_H_VY + i];
        let px = rx - sf[C_H_X + i];
        let py = ry - sf[C_H_Y + i];
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
            let gx = (sf[C_H_X + i] + vhx * tc) - (rx + vrx * tc);
            let gy = (sf[C_H_Y + i] + vhy * tc) - (ry + vry * tc);
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
    } else if (su[C_SHADOW_COLLIDED + e] != 0u || su[C_SHADOW_REACHED + e] == 0u) {
        stl = 1.0;
        spl = 1.0;
    } else {
        stl = min(f32(su[C_SHADOW_REACH_TICK + e]) / f32(su[C_TICK + e]), 1.0);
        spl = min(sf[C_SHADOW_PATH_LENGTH + e] / sf[C_M_PATH_LENGTH + e], 1.0);
    }
    outf[row + INFO_STL] = stl;
    outf[row + INFO_SPL] = spl;
}

// Per-episode sums and minima over the steps (spec 8.3).
fn accumulate_episode(e: u32, reward: f32) {
    let row = info_row(e);
    sf[C_EP_RETURN + e] += reward;
    sf[C_EP_MIN_HUMAN_DIST + e] = min(sf[C_EP_MIN_HUMAN_DIST + e], outf[row + INFO_MINIMUM_DISTANCE_TO_HUMAN]);
    sf[C_EP_MIN_OBSTACLE_DIST + e] = min(sf[C_EP_MIN_OBSTACLE_DIST + e], outf[row + INFO_MINIMUM_OBSTACLE_DISTANCE]);
    let avg = outf[row + INFO_AVERAGE_OBSTACLE_DISTANCE];
    if (!math_is_nan_bits(avg)) {
        sf[C_EP_SUM_AVG_OBSTACLE_DIST + e] += avg;
    }
    let ttc = outf[row + INFO_TIME_TO_COLLISION];
    if (ttc < 0.0) {
        sf[C_EP_SUM_TTC + e] += f32(params.episode_length);
    } else {
        sf[C_EP_SUM_TTC + e] += ttc;
    }
    sf[C_EP_SUM_DISCOMFORT_DSRNN + e] += outf[row + INFO_DISCOMFORT_DSRNN];
    sf[C_EP_SUM_SNGNN + e] += outf[row + INFO_SNGNN_REWARD];
}

// The statistics of the episode that just ended (order of the Rust EPISODE_KEYS).
fn write_episode(e: u32) {
    let row = info_row(e);
    let out = CO_EPISODE + e * SO_EPISODE;
    let length = f32(su[C_TICK + e]);
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
    outf[out + EP_RETURN] = sf[C_EP_RETURN + e];
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
    outf[out + EP_MINIMUM_DISTANCE_TO_HUMAN] = sf[C_EP_MIN_HUMAN_DIST + e];
    outf[out + EP_MINIMUM_OBSTACLE_DISTANCE] = sf[C_EP_MIN_OBSTACLE_DIST + e];
    outf[out + EP_AVERAGE_OBSTACLE_DISTANCE] = sf[C_EP_SUM_AVG_OBSTACLE_DIST + e] / length;
    outf[out + EP_TIME_TO_COLLISION] = sf[C_EP_SUM_TTC + e] / length;
    outf[out + EP_DISCOMFORT_DSRNN] = sf[C_EP_SUM_DISCOMFORT_DSRNN + e];
    outf[out + EP_DISCOMFORT_SNGNN] = sf[C_EP_SUM_SNGNN + e];
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= N_ENVS || su[C_STEPPING + e] == 0u) {
        return;
    }
    let row = info_row(e);
    let tick = f32(su[C_TICK + e]);
    progress(e);
    motion_statistics(e, tick);
    let min_human = min_human_distance(e);
    outf[row + INFO_MINIMUM_DISTANCE_TO_HUMAN] = min_human;
    if (min_human - params.robot_radius >= PERSONAL_SPACE) {
        su[C_M_COMPLIANT + e] += 1u;
    }
    outf[row + INFO_PERSONAL_SPACE_COMPLIANCE] = f32(su[C_M_COMPLIANT + e]) / tick;
    outf[row + INFO_TIME_TO_COLLISION] = time_to_collision(e);
    let obstacles = obstacle_distances(e);
    outf[row + INFO_MINIMUM_OBSTACLE_DISTANCE] = obstacles.x;
    outf[row + INFO_AVERAGE_OBSTACLE_DISTANCE] = obstacles.y;
    shadow_ratios(e);
    accumulate_episode(e, outf[CO_REWARD + e]);
    if (su[C_DONE + e] != 0u) {
        write_episode(e);
        outu[CO_EPISODE_DONE + e] = 1u;
    }
}
