//! Stage `metrics`: every info metric of docs/spec.md 8.2 for this step, the running accumulators
//! behind them, and, when the episode ends, its statistics as the paper's table aggregates them
//! (docs/spec.md 8.3).
//!
//! Definitions are 0.1.1's (docs/fidelity.md): STALLED_TIME is in seconds, personal space does not
//! subtract the human radius, laptops are not obstacles, accelerations and jerks are taken on the
//! robot-frame command (v_x, v_y) and ignore ω. TIME_TO_COLLISION covers laptop users properly
//! (0.1.1 re-evaluates a leaked loop variable instead).

use crate::params::StepParams;
use crate::spec::{EPISODE_KEYS, info};
use crate::state::StateChunk;

use super::Batch;

/// Personal-space threshold (m) between the robot's surface and a human's centre ("the value
/// used in SEAN 2.0").
pub const PERSONAL_SPACE: f32 = 0.45;

/// Update the metrics of environment `e` and write them into its info row.
pub fn metrics(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    let s = &mut b.s;
    let row = &mut b.o.info[e * b.o.strides.info()..(e + 1) * b.o.strides.info()];
    let tick = s.tick[e] as f32;
    progress(p, s, e, row);
    motion_statistics(p, s, e, tick, row);
    let min_human = min_human_distance(s, e);
    row[info::MINIMUM_DISTANCE_TO_HUMAN] = min_human;
    if min_human - p.robot_radius >= PERSONAL_SPACE {
        s.m_compliant[e] += 1;
    }
    row[info::PERSONAL_SPACE_COMPLIANCE] = s.m_compliant[e] as f32 / tick;
    row[info::TIME_TO_COLLISION] = time_to_collision(p, s, e);
    let (min_obstacle, avg_obstacle) = obstacle_distances(p, s, e);
    row[info::MINIMUM_OBSTACLE_DISTANCE] = min_obstacle;
    row[info::AVERAGE_OBSTACLE_DISTANCE] = avg_obstacle;
    shadow_ratios(s, e, row);
    accumulate_episode(p, s, e, b.o.reward[e], row);
    if s.done[e] != 0 {
        let stats = &mut b.o.episode[e * b.o.strides.episode()..(e + 1) * b.o.strides.episode()];
        write_episode(p, s, e, row, stats);
        b.o.episode_done[e] = 1;
        b.o.episode_seed_lo[e] = s.seed_lo[e];
        b.o.episode_seed_hi[e] = s.seed_hi[e];
    }
}

/// FAILURE_TO_PROGRESS, STALLED_TIME, TIME_TO_REACH_GOAL, PATH_LENGTH.
fn progress(p: &StepParams, s: &mut StateChunk, e: usize, row: &mut [f32]) {
    let dx = s.goal_x[e] - s.robot_x[e];
    let dy = s.goal_y[e] - s.robot_y[e];
    let d = (dx * dx + dy * dy).sqrt();
    if d > s.m_prev_goal_dist[e] {
        s.m_failure_to_progress[e] += 1;
    }
    s.m_prev_goal_dist[e] = d;
    let v = speed(s.robot_vx[e], s.robot_vy[e]);
    if v == 0.0 {
        s.m_stalled_time[e] += p.dt;
    }
    s.m_path_length[e] += p.dt * v;
    row[info::FAILURE_TO_PROGRESS] = s.m_failure_to_progress[e] as f32;
    row[info::STALLED_TIME] = s.m_stalled_time[e];
    row[info::TIME_TO_REACH_GOAL] = if row[info::SUCCESS] != 0.0 {
        s.tick[e] as f32 * p.dt
    } else {
        f32::NAN
    };
    row[info::PATH_LENGTH] = s.m_path_length[e];
}

/// The magnitude of the vector (x, y).
#[inline]
pub fn speed(x: f32, y: f32) -> f32 {
    (x * x + y * y).sqrt()
}

/// Running min / mean / max of a magnitude over the episode's `tick` steps.
#[inline]
fn running(min: &mut f32, avg: &mut f32, max: &mut f32, value: f32, tick: f32) {
    *min = min.min(value);
    *max = max.max(value);
    *avg = (*avg * (tick - 1.0) + value) / tick;
}

/// This step's acceleration (m/s²) of the robot-frame linear command (v_x, v_y): valid until
/// `metrics` stores the command as the previous one.
#[inline]
pub fn command_acceleration(p: &StepParams, s: &StateChunk, e: usize) -> (f32, f32) {
    (
        (s.robot_vx[e] - s.m_prev_vx[e]) / p.dt,
        (s.robot_vy[e] - s.m_prev_vy[e]) / p.dt,
    )
}

/// V, A and JERK statistics of the robot-frame linear command.
fn motion_statistics(p: &StepParams, s: &mut StateChunk, e: usize, tick: f32, row: &mut [f32]) {
    let (vx, vy) = (s.robot_vx[e], s.robot_vy[e]);
    let (ax, ay) = command_acceleration(p, s, e);
    let jx = (ax - s.m_prev_ax[e]) / p.dt;
    let jy = (ay - s.m_prev_ay[e]) / p.dt;
    running(
        &mut s.m_v_min[e],
        &mut s.m_v_avg[e],
        &mut s.m_v_max[e],
        speed(vx, vy),
        tick,
    );
    running(
        &mut s.m_a_min[e],
        &mut s.m_a_avg[e],
        &mut s.m_a_max[e],
        speed(ax, ay),
        tick,
    );
    running(
        &mut s.m_j_min[e],
        &mut s.m_j_avg[e],
        &mut s.m_j_max[e],
        speed(jx, jy),
        tick,
    );
    s.m_prev_vx[e] = vx;
    s.m_prev_vy[e] = vy;
    s.m_prev_ax[e] = ax;
    s.m_prev_ay[e] = ay;
    row[info::V_MIN] = s.m_v_min[e];
    row[info::V_AVG] = s.m_v_avg[e];
    row[info::V_MAX] = s.m_v_max[e];
    row[info::A_MIN] = s.m_a_min[e];
    row[info::A_AVG] = s.m_a_avg[e];
    row[info::A_MAX] = s.m_a_max[e];
    row[info::JERK_MIN] = s.m_j_min[e];
    row[info::JERK_AVG] = s.m_j_avg[e];
    row[info::JERK_MAX] = s.m_j_max[e];
}

/// Smallest robot-human centre distance (m); +inf without humans.
pub fn min_human_distance(s: &StateChunk, e: usize) -> f32 {
    let hb = e * s.strides.humans;
    (hb..hb + s.n_humans[e] as usize)
        .map(|i| speed(s.h_x[i] - s.robot_x[e], s.h_y[i] - s.robot_y[e]))
        .fold(f32::INFINITY, f32::min)
}

/// Steps until the robot and a human touch at constant velocities, the smallest over the humans;
/// 0 when already touching, -1 when none approaches (docs/spec.md 8.2).
pub fn time_to_collision(p: &StepParams, s: &StateChunk, e: usize) -> f32 {
    let (vrx, vry) = super::robot_motion::robot_world_velocity(s, e);
    let (rx, ry) = (s.robot_x[e], s.robot_y[e]);
    let reach = p.robot_radius + p.human_radius;
    let hb = e * s.strides.humans;
    let mut best = f32::INFINITY;
    for i in hb..hb + s.n_humans[e] as usize {
        let (vhx, vhy) = (s.h_vx[i], s.h_vy[i]);
        let (px, py) = (rx - s.h_x[i], ry - s.h_y[i]);
        let dist = speed(px, py);
        let t = if dist <= reach {
            0.0
        } else {
            let (vx, vy) = (vhx - vrx, vhy - vry);
            let approach = (vx * px + vy * py) / dist;
            if approach <= 0.0 {
                continue;
            }
            let t = dist / approach;
            let gx = (s.h_x[i] + vhx * t) - (rx + vrx * t);
            let gy = (s.h_y[i] + vhy * t) - (ry + vry * t);
            if speed(gx, gy) > reach {
                continue;
            }
            (t / p.dt).ceil()
        };
        best = best.min(t);
    }
    if best.is_finite() { best } else { -1.0 }
}

/// Minimum and mean distance (m) from the robot centre to plants (surface), tables and walls
/// (nearest point); laptops excluded, robot radius not subtracted. (+inf, NaN) without obstacles.
pub fn obstacle_distances(p: &StepParams, s: &StateChunk, e: usize) -> (f32, f32) {
    let (rx, ry) = (s.robot_x[e], s.robot_y[e]);
    let (mut min, mut sum, mut n) = (f32::INFINITY, 0.0f32, 0u32);
    let mut add = |d: f32| {
        min = min.min(d);
        sum += d;
        n += 1;
    };
    let pb = e * s.strides.plants;
    for i in pb..pb + s.n_plants[e] as usize {
        add(speed(s.p_x[i] - rx, s.p_y[i] - ry) - p.plant_radius);
    }
    for t in 0..s.n_tables[e] as usize {
        add(super::world::table_rect(p, s, e, t)
            .distance_sq(rx, ry)
            .sqrt());
    }
    for w in 0..s.n_walls[e] as usize {
        add(super::world::wall_rect(p, s, e, w)
            .distance_sq(rx, ry)
            .sqrt());
    }
    if n == 0 {
        (f32::INFINITY, f32::NAN)
    } else {
        (min, sum / n as f32)
    }
}

/// STL and SPL: 0 unless this step succeeded; then 1 when the shadow robot collided or has not
/// arrived yet, else the ratio of its time (path length) to the robot's, at most 1.
fn shadow_ratios(s: &StateChunk, e: usize, row: &mut [f32]) {
    let (stl, spl) = if row[info::SUCCESS] == 0.0 {
        (0.0, 0.0)
    } else if s.shadow_collided[e] != 0 || s.shadow_reached[e] == 0 {
        (1.0, 1.0)
    } else {
        let stl = (s.shadow_reach_tick[e] as f32 / s.tick[e] as f32).min(1.0);
        let spl = (s.shadow_path_length[e] / s.m_path_length[e]).min(1.0);
        (stl, spl)
    };
    row[info::STL] = stl;
    row[info::SPL] = spl;
}

/// Per-episode sums and minima over the steps (docs/spec.md 8.3).
fn accumulate_episode(p: &StepParams, s: &mut StateChunk, e: usize, reward: f32, row: &[f32]) {
    s.ep_return[e] += reward;
    s.ep_min_human_dist[e] = s.ep_min_human_dist[e].min(row[info::MINIMUM_DISTANCE_TO_HUMAN]);
    s.ep_min_obstacle_dist[e] = s.ep_min_obstacle_dist[e].min(row[info::MINIMUM_OBSTACLE_DISTANCE]);
    let avg = row[info::AVERAGE_OBSTACLE_DISTANCE];
    if !avg.is_nan() {
        s.ep_sum_avg_obstacle_dist[e] += avg;
    }
    let ttc = row[info::TIME_TO_COLLISION];
    s.ep_sum_ttc[e] += if ttc < 0.0 {
        p.episode_length as f32
    } else {
        ttc
    };
    s.ep_sum_discomfort_dsrnn[e] += row[info::DISCOMFORT_DSRNN];
    s.ep_sum_sngnn[e] += row[info::SNGNN_REWARD];
}

/// Index of a per-episode statistic by name.
#[expect(
    clippy::panic,
    reason = "evaluated at compile time: a wrong key fails the build"
)]
pub const fn episode_index(key: &str) -> usize {
    let mut i = 0;
    while i < EPISODE_KEYS.len() {
        if str_eq(EPISODE_KEYS[i], key) {
            return i;
        }
        i += 1;
    }
    panic!("unknown episode statistic");
}

const fn str_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The statistics of the episode that just ended (order of [`EPISODE_KEYS`]).
fn write_episode(p: &StepParams, s: &StateChunk, e: usize, row: &[f32], out: &mut [f32]) {
    let length = s.tick[e] as f32;
    let success = row[info::SUCCESS];
    let collision = row[info::COLLISION];
    let copies = [
        ("FAILURE_TO_PROGRESS", info::FAILURE_TO_PROGRESS),
        ("STALLED_TIME", info::STALLED_TIME),
        ("PATH_LENGTH", info::PATH_LENGTH),
        ("V_MIN", info::V_MIN),
        ("V_AVG", info::V_AVG),
        ("V_MAX", info::V_MAX),
        ("A_MIN", info::A_MIN),
        ("A_AVG", info::A_AVG),
        ("A_MAX", info::A_MAX),
        ("JERK_MIN", info::JERK_MIN),
        ("JERK_AVG", info::JERK_AVG),
        ("JERK_MAX", info::JERK_MAX),
        ("PERSONAL_SPACE_COMPLIANCE", info::PERSONAL_SPACE_COMPLIANCE),
        ("STL", info::STL),
        ("SPL", info::SPL),
    ];
    for (key, k) in copies {
        out[episode_index(key)] = row[k];
    }
    let set = |out: &mut [f32], key: &str, v: f32| out[episode_index(key)] = v;
    set(out, "return", s.ep_return[e]);
    set(out, "length", length);
    set(out, "success", success);
    set(out, "collision", collision);
    set(out, "collision_human", row[info::COLLISION_HUMAN]);
    set(out, "collision_object", row[info::COLLISION_OBJECT]);
    set(out, "collision_wall", row[info::COLLISION_WALL]);
    set(out, "timeout", row[info::TIMEOUT]);
    set(out, "out_of_map", row[info::OUT_OF_MAP]);
    set(
        out,
        "time_taken",
        if collision != 0.0 {
            p.episode_length as f32
        } else {
            length
        },
    );
    let ttrg = if success != 0.0 {
        row[info::TIME_TO_REACH_GOAL]
    } else {
        p.episode_length as f32
    };
    set(out, "TIME_TO_REACH_GOAL", ttrg);
    set(out, "MINIMUM_DISTANCE_TO_HUMAN", s.ep_min_human_dist[e]);
    set(out, "MINIMUM_OBSTACLE_DISTANCE", s.ep_min_obstacle_dist[e]);
    set(
        out,
        "AVERAGE_OBSTACLE_DISTANCE",
        s.ep_sum_avg_obstacle_dist[e] / length,
    );
    set(out, "TIME_TO_COLLISION", s.ep_sum_ttc[e] / length);
    set(out, "DISCOMFORT_DSRNN", s.ep_sum_discomfort_dsrnn[e]);
    set(out, "DISCOMFORT_SNGNN", s.ep_sum_sngnn[e]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_mean_matches_golden_accumulators() {
        // exp1 seed 3 after 5 steps at constant |v| = 0.04493: V_AVG = 0.04493,
        // A_AVG = 0.04493 / 5 (only the first step accelerates), JERK_AVG = 2 x 0.04493 / 5.
        let v = 0.044_93_f32;
        let (mut vmin, mut vavg, mut vmax) = (f32::INFINITY, 0.0, 0.0);
        let (mut amin, mut aavg, mut amax) = (f32::INFINITY, 0.0, 0.0);
        for t in 1..=5 {
            running(&mut vmin, &mut vavg, &mut vmax, v, t as f32);
            running(
                &mut amin,
                &mut aavg,
                &mut amax,
                if t == 1 { v } else { 0.0 },
                t as f32,
            );
        }
        assert!((vavg - v).abs() < 1e-8);
        assert!((aavg - v / 5.0).abs() < 1e-8, "{aavg}");
        assert_eq!((amin, amax), (0.0, v));
    }

    #[test]
    fn episode_keys_resolve() {
        assert_eq!(episode_index("return"), 0);
        assert_eq!(EPISODE_KEYS[episode_index("SPL")], "SPL");
    }
}
