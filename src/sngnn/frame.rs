//! The SNGNN input frame of one environment at the current step (docs/spec.md 7.2), as 0.1.1's
//! `RewardAPI.compute_sngnn_reward` builds it after the motion of a non-terminal step, quirks
//! included (they define the model's input, docs/fidelity.md):
//!
//! - Positions go into the robot frame (x forward, y left, f32 as the observation computes
//!   them), then into SNGNN's axes (x_s, y_s) = (−y_r, x_r): x to the robot's right, y ahead.
//! - Angles are a = −(π/2 + θ) with θ the entity's heading relative to the robot, wrapped to
//!   (−π, π]; a itself is not wrapped.
//! - "Velocities" are backward differences of the robot-frame pose over the step, rescaled to
//!   SNGNN's 0.2 s frame period and left in robot-frame axes: v = (previous − current) / (dt /
//!   0.2). The previous pose is relative to the previous robot pose, so they include the robot's
//!   own motion; relative headings are subtracted unwrapped.
//! - People: lone humans, group members, laptop users (human slot order, which is 0.1.1's).
//!   Objects: free laptops, laptops in use, plants (2r × 2r), tables (length × width).
//!   Interactions: per group, for every member pair i < j the entries j → i and i → j (the
//!   graph links both directions of each, so every ordered pair twice); per laptop user the
//!   entry laptop → human.
//! - The command is 0.1.1's conversion of the processed action to CoppeliaSim units:
//!   [min(9.4 v_x, 3.5), 0 or min(9.4 v_y, 3.5) (holonomic), clip(10.32 ω, ±4)].
//!
//! The previous poses live in the `sn_prev_*` columns, indexed by entity id − 1 (0.1.1 keys
//! them by id): filled at reset and by `set_state`, refreshed by [`record`].

use super::history::{self, FrameHead, Link, Object, Person};
use crate::math;
use crate::params::StepParams;
use crate::state::StateChunk;

/// Command conversion to CoppeliaSim units: advance per m/s.
pub const ADVANCE_SCALE: f32 = 9.4;
/// Largest advance command (SNGNN's `MAX_ADV`).
pub const MAX_ADVANCE: f32 = 3.5;
/// Command conversion: rotation per rad/s (10.32 × 0.3876 rad/s = 4).
pub const ROTATION_SCALE: f32 = 10.32;
/// Largest rotation command, either way (SNGNN's `MAX_ROT`).
pub const MAX_ROTATION: f32 = 4.0;
/// SNGNN's frame period (s): velocities are differences per this much time.
pub const FRAME_PERIOD: f32 = 0.2;

/// A robot pose (world frame: m, m, rad) and the transform into its frame, computed as the
/// observation computes it.
#[derive(Debug, Clone, Copy)]
pub struct RobotPose {
    x: f32,
    y: f32,
    theta: f32,
    cos: f32,
    sin: f32,
}

impl RobotPose {
    /// The pose (x, y, θ) (m, m, rad).
    pub fn new([x, y, theta]: [f32; 3]) -> Self {
        let (sin, cos) = math::sin_cos(theta);
        Self {
            x,
            y,
            theta,
            cos,
            sin,
        }
    }

    /// The current robot pose of local environment `e`.
    pub fn of(s: &StateChunk, e: usize) -> Self {
        Self::new([s.robot_x[e], s.robot_y[e], s.robot_theta[e]])
    }

    /// World point (m) → robot frame (m; x forward, y left).
    #[inline]
    pub fn local(&self, x: f32, y: f32) -> (f32, f32) {
        let dx = x - self.x;
        let dy = y - self.y;
        (self.cos * dx + self.sin * dy, self.cos * dy - self.sin * dx)
    }

    /// World point (m) → SNGNN axes (m; x right, y ahead): (−y_r, x_r).
    #[inline]
    pub fn sngnn(&self, x: f32, y: f32) -> (f32, f32) {
        let (lx, ly) = self.local(x, y);
        (-ly, lx)
    }

    /// The robot-frame pose of an entity at (x, y) (m) with heading `theta` (rad, world).
    #[inline]
    fn seen(&self, x: f32, y: f32, theta: f32) -> Seen {
        let (lx, ly) = self.local(x, y);
        Seen {
            x: lx,
            y: ly,
            theta: math::wrap_angle(theta - self.theta),
        }
    }
}

/// An entity's pose in the robot frame: position (m) and heading (rad, wrapped to (−π, π]).
#[derive(Debug, Clone, Copy)]
struct Seen {
    x: f32,
    y: f32,
    theta: f32,
}

impl Seen {
    /// The frame's record of entity `id` seen at `self` now and at `before` one step ago;
    /// `period_steps` = dt / 0.2 s.
    fn entry(&self, id: u32, before: Seen, period_steps: f32) -> Person {
        Person {
            id,
            x: -self.y,
            y: self.x,
            a: -(math::FRAC_PI_2 + self.theta),
            vx: (before.x - self.x) / period_steps,
            vy: (before.y - self.y) / period_steps,
            va: (before.theta - self.theta) / period_steps,
        }
    }
}

/// Push the current frame of local environment `e` into its history, then remember every
/// entity's robot-frame pose for the next step's velocities. Call once per non-terminal step,
/// after the motion (stage `sngnn_graph`); does nothing without a history (a config without the
/// SNGNN reward).
pub fn record(p: &StepParams, s: &mut StateChunk, e: usize) {
    if s.strides.frames == 0 {
        return;
    }
    let robot = RobotPose::of(s, e);
    let (gx, gy) = robot.sngnn(s.goal_x[e], s.goal_y[e]);
    let head = FrameHead {
        tick: s.tick[e],
        robot: [s.robot_x[e], s.robot_y[e], s.robot_theta[e]],
        goal: [gx, gy],
        command: command(p, s, e),
    };
    let slot = history::begin_frame(s, e, &head);
    let period_steps = p.dt / FRAME_PERIOD;
    // Each push reads an entity's previous pose and then remembers its current one.
    push_people(s, e, slot, &robot, period_steps);
    push_objects(p, s, e, slot, &robot, period_steps);
    push_links(s, e, slot);
}

/// A new episode of local environment `e`: an empty history and the reset poses as the
/// previous ones. Does nothing without a history.
pub fn start_episode(s: &mut StateChunk, e: usize) {
    if s.strides.frames == 0 {
        return;
    }
    history::clear(s, e);
    let c = s.strides.sngnn_entities;
    s.sn_prev_x[e * c..(e + 1) * c].fill(0.0);
    s.sn_prev_y[e * c..(e + 1) * c].fill(0.0);
    s.sn_prev_theta[e * c..(e + 1) * c].fill(0.0);
    remember_poses(s, e);
}

/// The command of the step in SNGNN units (docs/spec.md 7.2): advance, lateral advance (0 for a
/// differential-drive robot), rotation.
pub fn command(p: &StepParams, s: &StateChunk, e: usize) -> [f32; 3] {
    let advance = |v: f32| (ADVANCE_SCALE * v).min(MAX_ADVANCE);
    let lateral = if p.holonomic != 0 {
        advance(s.robot_vy[e])
    } else {
        0.0
    };
    let rotation = (ROTATION_SCALE * s.robot_w[e]).clamp(-MAX_ROTATION, MAX_ROTATION);
    [advance(s.robot_vx[e]), lateral, rotation]
}

/// Index of entity `id`'s previous pose in the `sn_prev_*` columns.
#[inline]
fn prev_index(s: &StateChunk, e: usize, id: u32) -> usize {
    let c = s.strides.sngnn_entities;
    assert!(
        id >= 1 && id as usize <= c,
        "entity id {id} outside 1..={c}: the SNGNN frame needs the ids of humans and objects to \
         be 1..=N (docs/spec.md 7.3; checked when a state document is loaded)"
    );
    e * c + id as usize - 1
}

fn previous(s: &StateChunk, e: usize, id: u32) -> Seen {
    let i = prev_index(s, e, id);
    Seen {
        x: s.sn_prev_x[i],
        y: s.sn_prev_y[i],
        theta: s.sn_prev_theta[i],
    }
}

fn remember(s: &mut StateChunk, e: usize, id: u32, seen: Seen) {
    let i = prev_index(s, e, id);
    s.sn_prev_x[i] = seen.x;
    s.sn_prev_y[i] = seen.y;
    s.sn_prev_theta[i] = seen.theta;
}

/// Remember the current robot-frame pose of every human and object of local environment `e`
/// as its previous pose (nothing to do without the SNGNN reward).
pub fn remember_poses(s: &mut StateChunk, e: usize) {
    if s.strides.sngnn_entities == 0 {
        return;
    }
    let robot = RobotPose::of(s, e);
    let c = s.strides;
    let hb = e * c.humans;
    for i in hb..hb + s.n_humans[e] as usize {
        let (id, seen) = (s.h_id[i], robot.seen(s.h_x[i], s.h_y[i], s.h_theta[i]));
        remember(s, e, id, seen);
    }
    let lb = e * c.laptops;
    for i in lb..lb + s.n_laptops[e] as usize {
        let (id, seen) = (s.l_id[i], robot.seen(s.l_x[i], s.l_y[i], s.l_theta[i]));
        remember(s, e, id, seen);
    }
    let pb = e * c.plants;
    for i in pb..pb + s.n_plants[e] as usize {
        let (id, seen) = (s.p_id[i], robot.seen(s.p_x[i], s.p_y[i], 0.0));
        remember(s, e, id, seen);
    }
    let tb = e * c.tables;
    for i in tb..tb + s.n_tables[e] as usize {
        let (id, seen) = (s.t_id[i], robot.seen(s.t_x[i], s.t_y[i], s.t_theta[i]));
        remember(s, e, id, seen);
    }
}

/// Every human, in slot order (0.1.1's: lone static, lone walking, group members, laptop users);
/// each one's pose is remembered for the next step's velocities.
fn push_people(s: &mut StateChunk, e: usize, slot: usize, robot: &RobotPose, period_steps: f32) {
    let hb = e * s.strides.humans;
    for i in hb..hb + s.n_humans[e] as usize {
        let id = s.h_id[i];
        let now = robot.seen(s.h_x[i], s.h_y[i], s.h_theta[i]);
        let person = now.entry(id, previous(s, e, id), period_steps);
        remember(s, e, id, now);
        history::push_person(s, e, slot, &person);
    }
}

/// Laptops (free ones, then those in use, in laptop-user order: 0.1.1 adds a used laptop right
/// after its user, and users come last), plants, tables.
fn push_objects(
    p: &StepParams,
    s: &mut StateChunk,
    e: usize,
    slot: usize,
    robot: &RobotPose,
    period_steps: f32,
) {
    let c = s.strides;
    let push = |s: &mut StateChunk, id: u32, now: Seen, size: [f32; 2]| {
        let object = Object {
            pose: now.entry(id, previous(s, e, id), period_steps),
            size_x: size[0],
            size_y: size[1],
        };
        remember(s, e, id, now);
        history::push_object(s, e, slot, &object);
    };
    let lb = e * c.laptops;
    for i in lb..lb + s.n_laptops[e] as usize {
        let (id, now) = (s.l_id[i], robot.seen(s.l_x[i], s.l_y[i], s.l_theta[i]));
        push(s, id, now, [p.laptop_length, p.laptop_width]);
    }
    let pb = e * c.plants;
    let diameter = 2.0 * p.plant_radius;
    for i in pb..pb + s.n_plants[e] as usize {
        let (id, now) = (s.p_id[i], robot.seen(s.p_x[i], s.p_y[i], 0.0));
        push(s, id, now, [diameter, diameter]);
    }
    let tb = e * c.tables;
    for i in tb..tb + s.n_tables[e] as usize {
        let (id, now) = (s.t_id[i], robot.seen(s.t_x[i], s.t_y[i], s.t_theta[i]));
        push(s, id, now, [p.table_length, p.table_width]);
    }
}

/// Groups in order (moving, then standing): members i < j give j → i, then i → j; then one
/// laptop → human entry per laptop user.
fn push_links(s: &mut StateChunk, e: usize, slot: usize) {
    let c = s.strides;
    let hb = e * c.humans;
    let gb = e * c.groups;
    for g in gb..gb + s.n_groups[e] as usize {
        let first = hb + s.g_first[g] as usize;
        let n = s.g_count[g] as usize;
        for i in first..first + n {
            for j in i + 1..first + n {
                let (a, b) = (s.h_id[i], s.h_id[j]);
                history::push_link(s, e, slot, Link { src: b, dst: a });
                history::push_link(s, e, slot, Link { src: a, dst: b });
            }
        }
    }
    let ub = e * c.laptop_users;
    let lb = e * c.laptops;
    for u in ub..ub + s.n_laptop_users[e] as usize {
        let human = s.h_id[hb + s.lu_human[u] as usize];
        let laptop = s.l_id[lb + s.lu_laptop[u] as usize];
        history::push_link(
            s,
            e,
            slot,
            Link {
                src: laptop,
                dst: human,
            },
        );
    }
}

/// The end points (x1, y1, x2, y2) (m, SNGNN axes) of wall `w` (local wall index) of
/// environment `e`, seen from `robot`: centre ∓ L/2 (cos θ, sin θ), as 0.1.1 lists walls.
pub fn wall_ends(s: &StateChunk, e: usize, w: usize, robot: &RobotPose) -> [f32; 4] {
    let i = e * s.strides.walls + w;
    let half = 0.5 * s.w_length[i];
    let (dx, dy) = (half * s.w_cos[i], half * s.w_sin[i]);
    let (x1, y1) = robot.sngnn(s.w_x[i] - dx, s.w_y[i] - dy);
    let (x2, y2) = robot.sngnn(s.w_x[i] + dx, s.w_y[i] + dy);
    [x1, y1, x2, y2]
}
