//! Stage `reward`: the DSRNN-style reward (docs/spec.md 6.2) or SNGNN-v2's (docs/spec.md 6.3).
//! Terminal steps get the outcome's constant; other steps the potential-based distance term, the
//! discomfort term (DSRNN's predicted clearance, or SNGNN-v2's score of the scene, which stages
//! `sngnn_graph` and `sngnn_score` leave in `r_discomfort_sngnn`) and the alive term. The
//! reward's info values persist: a terminal step reports those of the previous step (0.1.1).
//!
//! Fixed 0.1.1 bugs (docs/fidelity.md): the robot velocity uses the robot's heading once (0.1.1
//! advances it by ω·dt twice); a pseudo-human's heading is its own group's (0.1.1 takes it from a
//! leaked loop variable).

use crate::geometry::origin_segment_distance;
use crate::math;
use crate::params::StepParams;
use crate::spec::info;
use crate::state::StateChunk;

use super::robot_motion::robot_world_velocity;
use super::{Batch, metrics};

/// Score the step of environment `e`.
pub fn reward(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    let row = e * b.o.strides.info();
    let flag = |k: usize| b.o.info[row + k] != 0.0;
    let r = if flag(info::OUT_OF_MAP) {
        p.reward_out_of_map
    } else if flag(info::SUCCESS) {
        p.reward_reach
    } else if flag(info::COLLISION) {
        p.reward_collision
    } else if flag(info::TIMEOUT) {
        p.reward_timeout
    } else {
        step_reward(p, &mut b.s, e)
    };
    b.o.reward[e] = r;
    let s = &b.s;
    let out = &mut b.o.info[row..];
    out[info::DISCOMFORT_SNGNN] = s.r_discomfort_sngnn[e];
    out[info::DISCOMFORT_DSRNN] = s.r_discomfort_dsrnn[e];
    out[info::DISTANCE_REWARD] = s.r_distance[e];
    out[info::ALIVE_REWARD] = s.r_alive[e];
    out[info::SNGNN_REWARD] = s.r_sngnn[e];
}

/// Whether the reward scores environment `e`'s step with its terms (distance, discomfort, alive)
/// rather than an outcome's constant: the environment steps and termination raised no outcome
/// flag. The SNGNN-v2 stages before the reward score exactly these steps.
pub fn scores_terms(b: &Batch<'_>, e: usize) -> bool {
    let row = e * b.o.strides.info();
    let flag = |k: usize| b.o.info[row + k] != 0.0;
    b.s.stepping[e] != 0
        && !flag(info::OUT_OF_MAP)
        && !flag(info::SUCCESS)
        && !flag(info::COLLISION)
        && !flag(info::TIMEOUT)
}

/// The reward of a non-terminal step; updates the reward memory.
fn step_reward(p: &StepParams, s: &mut StateChunk, e: usize) -> f32 {
    let dx = s.goal_x[e] - s.robot_x[e];
    let dy = s.goal_y[e] - s.robot_y[e];
    let d = (dx * dx + dy * dy).sqrt();
    // 0 on the first step: the previous distance is unknown to the reward (0.1.1).
    let r_dist = if s.r_has_prev[e] != 0 {
        -(p.reward_distance_scale * (d - s.r_prev_dist[e]))
    } else {
        0.0
    };
    let r_disc = dsrnn_discomfort(p, min_predicted_clearance(p, s, e));
    s.r_prev_dist[e] = d;
    s.r_has_prev[e] = 1;
    s.r_distance[e] = r_dist;
    s.r_discomfort_dsrnn[e] = r_disc;
    s.r_alive[e] = p.reward_alive;
    let r = if p.reward_kind == REWARD_SNGNN {
        // Stage sngnn_score left the network's raw output here.
        let discomfort = clip_sngnn(s.r_discomfort_sngnn[e]);
        s.r_discomfort_sngnn[e] = discomfort;
        s.r_sngnn[e] = discomfort - 1.0;
        // docs/spec.md 6.3: the DSRNN discomfort is computed for the info only.
        (discomfort - 1.0) * SNGNN_WEIGHT + r_dist + p.reward_alive
    } else {
        s.r_discomfort_sngnn[e] = 0.0;
        r_disc + r_dist + p.reward_alive
    };
    with_extra_terms(p, s, e, r)
}

/// The DSRNN discomfort term (docs/spec.md 6.2) of a predicted clearance `d_min` (m):
/// (d_min − 0.6)·0.5·dt below the discomfort distance, else 0.
pub fn dsrnn_discomfort(p: &StepParams, d_min: f32) -> f32 {
    if d_min < p.reward_discomfort_distance {
        (d_min - p.reward_discomfort_distance) * p.reward_discomfort_factor * p.dt
    } else {
        0.0
    }
}

/// `StepParams::reward_kind` of the SNGNN-v2 reward (the shaders get it from the prelude).
pub const REWARD_SNGNN: u32 = 1;
/// 0.1.1's weight of the SNGNN term (the shaders get it from the prelude).
pub const SNGNN_WEIGHT: f32 = 1.0;

/// SNGNN-v2's discomfort in [0, 1] from the network's raw output `q1` (docs/spec.md 6.3).
pub fn clip_sngnn(q1: f32) -> f32 {
    q1.clamp(0.0, 1.0)
}

/// `r` plus the weighted terms beyond 0.1.1 (`reward.*_weight`). A term whose weight is 0 is not
/// evaluated at all, so 0.1.1's reward stays bit-exact (not even `+ 0.0`, which turns -0 into +0)
/// and an infinite distance (no humans, no obstacles) never meets a zero weight.
fn with_extra_terms(p: &StepParams, s: &StateChunk, e: usize, mut r: f32) -> f32 {
    if p.reward_personal_space_weight != 0.0 {
        let clearance = metrics::min_human_distance(s, e) - p.robot_radius;
        let intrusion = (p.reward_personal_space_distance - clearance).max(0.0);
        r += p.reward_personal_space_weight * intrusion;
    }
    if p.reward_obstacle_weight != 0.0 {
        let clearance = metrics::obstacle_distances(p, s, e).0 - p.robot_radius;
        let intrusion = (p.reward_obstacle_distance - clearance).max(0.0);
        r += p.reward_obstacle_weight * intrusion;
    }
    if p.reward_stalled_weight != 0.0 && metrics::speed(s.robot_vx[e], s.robot_vy[e]) == 0.0 {
        r += p.reward_stalled_weight;
    }
    if p.reward_acceleration_weight != 0.0 {
        let (ax, ay) = metrics::command_acceleration(p, s, e);
        r += p.reward_acceleration_weight * metrics::speed(ax, ay);
    }
    r
}

/// The smallest clearance (m) between the robot and any human over the next dt, assuming
/// constant relative velocity: the distance from the origin to the segment travelled by the
/// relative position, minus both radii. +inf without humans.
pub fn min_predicted_clearance(p: &StepParams, s: &StateChunk, e: usize) -> f32 {
    let (vrx, vry) = robot_world_velocity(s, e);
    let (rx, ry) = (s.robot_x[e], s.robot_y[e]);
    // (x, y): the human's position (m); (hvx, hvy): its world velocity (m/s).
    let clearance = |x: f32, y: f32, hvx: f32, hvy: f32| {
        let px = x - rx;
        let py = y - ry;
        let vx = hvx - vrx;
        let vy = hvy - vry;
        origin_segment_distance(px, py, vx * p.dt, vy * p.dt) - p.human_radius - p.robot_radius
    };
    let hb = e * s.strides.humans;
    let mut d_min = f32::INFINITY;
    for i in hb..hb + s.n_humans[e] as usize {
        d_min = d_min.min(clearance(s.h_x[i], s.h_y[i], s.h_vx[i], s.h_vy[i]));
    }
    if p.dsrnn_pseudo_humans != 0 {
        let gb = e * s.strides.groups;
        for g in gb..gb + s.n_groups[e] as usize {
            let first = hb + s.g_first[g] as usize;
            let n = s.g_count[g] as usize;
            let mean_speed = s.h_speed[first..first + n].iter().sum::<f32>() / n as f32;
            let (sn, c) = math::sin_cos(s.h_theta[first]);
            d_min = d_min.min(clearance(
                s.g_x[g],
                s.g_y[g],
                mean_speed * c,
                mean_speed * sn,
            ));
        }
        let ub = e * s.strides.laptop_users;
        let lb = e * s.strides.laptops;
        for u in ub..ub + s.n_laptop_users[e] as usize {
            let h = hb + s.lu_human[u] as usize;
            let l = lb + s.lu_laptop[u] as usize;
            let cx = 0.5 * (s.h_x[h] + s.l_x[l]);
            let cy = 0.5 * (s.h_y[h] + s.l_y[l]);
            d_min = d_min.min(clearance(cx, cy, 0.0, 0.0));
        }
    }
    d_min
}
