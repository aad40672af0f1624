//! Stage `formation` (docs/spec.md 4.1 step 9, 4.5): the bookkeeping of formations in progress,
//! after the motion and goal re-sampling of the step.
//!
//! A forming crowd: a walker within its goal radius of its slot takes the slot's heading; when
//! every walker is there the crowd forms (laid out anew around the formation centre, standing or,
//! with probability 1/2, moving to a new goal). If instead the walkers have stayed within
//! `group radius + human radius` of their centroid for 25 consecutive steps, an "approximate"
//! standing group forms where they are, its members facing their centroid; its stored centre is
//! that of placeholder members laid out around the centroid, as 0.1.1 keeps it (docs/spec.md 14).
//!
//! A walker heading for a laptop seat sits down when within its goal radius of the seat: it is
//! snapped to the seat pose and becomes a laptop user (keeping its speed, as 0.1.1 does).

use crate::limits::MAX_GROUP;
use crate::math;
use crate::params::StepParams;
use crate::rng::RngStream;
use crate::scenario::place::{self, Pose};
use crate::spec::event;
use crate::state::{NONE, StateChunk, forming, group_kind, policy, role};

use super::Batch;
use super::regroup;

/// RNG stream kind of formation completions (`sub` = tick).
pub const STREAM_FORMATION: u32 = 5;

/// Consecutive steps of walkers staying together after which an approximate crowd forms.
pub const APPROXIMATE_AFTER: u32 = 25;

/// Advance the formations of environment `e`.
pub fn formation(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    let events = b.o.strides.events();
    let counts = &mut b.o.events[e * events..(e + 1) * events];
    let s = &mut b.s;
    if s.cf_active[e] != 0 {
        let mut rng = super::step_stream(s, e, STREAM_FORMATION);
        match crowd_progress(p, s, e, &mut rng) {
            Progress::Formed => counts[event::CROWD_FORMATION_COMPLETE] += 1,
            Progress::Approximate => counts[event::CROWD_FORMATION_APPROXIMATE] += 1,
            Progress::Walking => {}
        }
    }
    if s.lf_active[e] != 0 && seat_reached(p, s, e) {
        sit_down(p, s, e);
        counts[event::LAPTOP_FORMATION_COMPLETE] += 1;
    }
}

enum Progress {
    Walking,
    Formed,
    Approximate,
}

fn distance(ax: f32, ay: f32, bx: f32, by: f32) -> f32 {
    let (dx, dy) = (ax - bx, ay - by);
    (dx * dx + dy * dy).sqrt()
}

/// Slot headings for arrived walkers, then completion (exact, else approximate).
fn crowd_progress(p: &StepParams, s: &mut StateChunk, e: usize, rng: &mut RngStream) -> Progress {
    let hb = e * s.strides.humans;
    let sb = e * s.strides.group_size;
    let n = s.cf_count[e] as usize;
    let mut all_arrived = true;
    for k in sb..sb + n {
        let i = hb + s.cf_human[k] as usize;
        if distance(s.h_x[i], s.h_y[i], s.cf_slot_x[k], s.cf_slot_y[k]) < p.human_goal_radius {
            set_heading(s, i, s.cf_slot_theta[k]);
        } else {
            all_arrived = false;
        }
    }
    if all_arrived {
        form_crowd(p, s, e, rng);
        return Progress::Formed;
    }
    let (cx, cy) = walkers_centroid(s, e);
    let reach = p.group_radius + p.human_radius;
    let together = (sb..sb + n).all(|k| {
        let i = hb + s.cf_human[k] as usize;
        distance(s.h_x[i], s.h_y[i], cx, cy) < reach
    });
    s.cf_close_steps[e] = if together { s.cf_close_steps[e] + 1 } else { 0 };
    if s.cf_close_steps[e] >= APPROXIMATE_AFTER {
        form_approximate_crowd(p, s, e, rng, cx, cy);
        return Progress::Approximate;
    }
    Progress::Walking
}

/// Heading (rad) of human slot `i`, keeping its speed; the cached world velocity follows.
fn set_heading(s: &mut StateChunk, i: usize, theta: f32) {
    let (sn, c) = math::sin_cos(theta);
    s.h_theta[i] = theta;
    s.h_vx[i] = s.h_speed[i] * c;
    s.h_vy[i] = s.h_speed[i] * sn;
}

fn walkers_centroid(s: &StateChunk, e: usize) -> (f32, f32) {
    let hb = e * s.strides.humans;
    let sb = e * s.strides.group_size;
    let n = s.cf_count[e] as usize;
    let (mut x, mut y) = (0.0f32, 0.0f32);
    for k in sb..sb + n {
        let i = hb + s.cf_human[k] as usize;
        x += s.h_x[i];
        y += s.h_y[i];
    }
    (x / n as f32, y / n as f32)
}

/// A new group slot `g` with the forming walkers as members, in formation order.
fn new_group(p: &StepParams, s: &mut StateChunk, e: usize, kind: u32) -> usize {
    let g = e * s.strides.groups + s.n_groups[e] as usize;
    assert!(
        s.n_groups[e] < s.strides.groups as u32,
        "group capacity {} exhausted by crowd formation",
        s.strides.groups
    );
    s.n_groups[e] += 1;
    s.g_kind[g] = kind;
    s.g_dispersable[g] = 1;
    s.g_seq[g] = regroup::next_seq(s, e);
    s.g_vx[g] = 0.0;
    s.g_vy[g] = 0.0;
    // The members are the walkers that formed the crowd, with their human goal radius (0.1.1
    // swaps them into the placeholder group); a moving one's arrival is tested with it.
    s.g_member_goal_radius[g] = p.human_goal_radius;
    let hb = e * s.strides.humans;
    let sb = e * s.strides.group_size;
    let member_role = if kind == group_kind::MOVING {
        role::MOVING_GROUP
    } else {
        role::STANDING_GROUP
    };
    for k in sb..sb + s.cf_count[e] as usize {
        let i = hb + s.cf_human[k] as usize;
        s.h_role[i] = member_role;
        s.h_group[i] = (g - e * s.strides.groups) as u32;
        s.h_forming[i] = forming::NONE;
        s.h_seq[i] = regroup::next_seq(s, e);
    }
    g
}

/// Every walker is at its slot: lay the crowd out anew around the formation centre (members
/// facing it, speeds kept), standing or, with probability 1/2, moving to a new group goal.
fn form_crowd(p: &StepParams, s: &mut StateChunk, e: usize, rng: &mut RngStream) {
    let n = s.cf_count[e] as usize;
    let mut poses: [Pose; MAX_GROUP] = [(0.0, 0.0, 0.0); MAX_GROUP];
    place::group_layout(p, rng, s.cf_x[e], s.cf_y[e], n, true, &mut poses);
    let moving = rng.chance(0.5);
    let g = new_group(
        p,
        s,
        e,
        if moving {
            group_kind::MOVING
        } else {
            group_kind::STANDING
        },
    );
    let hb = e * s.strides.humans;
    let sb = e * s.strides.group_size;
    let (mut cx, mut cy) = (0.0f32, 0.0f32);
    for (k, &(x, y, theta)) in poses.iter().enumerate().take(n) {
        let i = hb + s.cf_human[sb + k] as usize;
        s.h_x[i] = x;
        s.h_y[i] = y;
        set_heading(s, i, theta);
        cx += x;
        cy += y;
    }
    s.g_x[g] = cx / n as f32;
    s.g_y[g] = cy / n as f32;
    if moving {
        let goal = super::goals::sample_goal(p, s, e, rng, p.group_goal_radius);
        let (gx, gy) = goal.map_or((s.g_x[g], s.g_y[g]), |d| (d.x, d.y));
        s.g_goal_x[g] = gx;
        s.g_goal_y[g] = gy;
        for k in sb..sb + n {
            let i = hb + s.cf_human[k] as usize;
            s.h_goal_x[i] = gx;
            s.h_goal_y[i] = gy;
        }
    }
    end_crowd_formation(p, s, e);
}

/// The walkers stayed together: a standing group where they are, members facing their
/// centroid; its stored centre comes from placeholder members laid out around the centroid.
fn form_approximate_crowd(
    p: &StepParams,
    s: &mut StateChunk,
    e: usize,
    rng: &mut RngStream,
    cx: f32,
    cy: f32,
) {
    let n = s.cf_count[e] as usize;
    let mut poses: [Pose; MAX_GROUP] = [(0.0, 0.0, 0.0); MAX_GROUP];
    place::group_layout(p, rng, cx, cy, n, true, &mut poses);
    let g = new_group(p, s, e, group_kind::STANDING);
    let (mut px, mut py) = (0.0f32, 0.0f32);
    for &(x, y, _) in poses.iter().take(n) {
        px += x;
        py += y;
    }
    s.g_x[g] = px / n as f32;
    s.g_y[g] = py / n as f32;
    let hb = e * s.strides.humans;
    let sb = e * s.strides.group_size;
    for k in sb..sb + n {
        let i = hb + s.cf_human[k] as usize;
        set_heading(s, i, math::atan2(cy - s.h_y[i], cx - s.h_x[i]));
    }
    end_crowd_formation(p, s, e);
}

fn end_crowd_formation(p: &StepParams, s: &mut StateChunk, e: usize) {
    clear_crowd_formation(s, e);
    regroup::canonicalize(p, s, e);
}

/// No crowd forming in environment `e`: every column of the formation zeroed, as in a state
/// loaded from a document without one.
pub fn clear_crowd_formation(s: &mut StateChunk, e: usize) {
    s.cf_active[e] = 0;
    s.cf_count[e] = 0;
    s.cf_close_steps[e] = 0;
    s.cf_x[e] = 0.0;
    s.cf_y[e] = 0.0;
    let sb = e * s.strides.group_size;
    let slots = sb..sb + s.strides.group_size;
    s.cf_slot_x[slots.clone()].fill(0.0);
    s.cf_slot_y[slots.clone()].fill(0.0);
    s.cf_slot_theta[slots.clone()].fill(0.0);
    s.cf_human[slots].fill(0);
}

/// No walker heading for a laptop in environment `e` (columns zeroed, as above).
pub fn clear_laptop_formation(s: &mut StateChunk, e: usize) {
    s.lf_active[e] = 0;
    s.lf_human[e] = 0;
    s.lf_laptop[e] = 0;
    s.lf_seat_x[e] = 0.0;
    s.lf_seat_y[e] = 0.0;
    s.lf_seat_theta[e] = 0.0;
}

fn seat_reached(p: &StepParams, s: &StateChunk, e: usize) -> bool {
    let i = e * s.strides.humans + s.lf_human[e] as usize;
    distance(s.h_x[i], s.h_y[i], s.lf_seat_x[e], s.lf_seat_y[e]) < p.human_goal_radius
}

/// The walker sits at the laptop: snapped to the seat pose, a new (dispersable) laptop user.
fn sit_down(p: &StepParams, s: &mut StateChunk, e: usize) {
    let i = e * s.strides.humans + s.lf_human[e] as usize;
    let l = e * s.strides.laptops + s.lf_laptop[e] as usize;
    let u_local = s.n_laptop_users[e] as usize;
    assert!(
        u_local < s.strides.laptop_users,
        "laptop-user capacity {} exhausted",
        s.strides.laptop_users
    );
    let u = e * s.strides.laptop_users + u_local;
    s.n_laptop_users[e] += 1;
    s.lu_human[u] = s.lf_human[e];
    s.lu_laptop[u] = s.lf_laptop[e];
    s.lu_dispersable[u] = 1;
    s.lu_seq[u] = regroup::next_seq(s, e);
    s.l_user[l] = u_local as u32;
    s.h_x[i] = s.lf_seat_x[e];
    s.h_y[i] = s.lf_seat_y[e];
    set_heading(s, i, s.lf_seat_theta[e]);
    s.h_role[i] = role::LAPTOP_USER;
    s.h_laptop_user[i] = u_local as u32;
    s.h_group[i] = NONE;
    s.h_forming[i] = forming::NONE;
    s.h_policy[i] = policy::ORCA;
    s.h_seq[i] = regroup::next_seq(s, e);
    clear_laptop_formation(s, e);
    regroup::canonicalize(p, s, e);
}
