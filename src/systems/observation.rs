//! Stage `observation` (spec section 5): the robot record and one 14-float record per entity, in
//! the robot frame (x forward, y left), laid out as [`crate::spec::ObsLayout`] says.
//!
//! Conventions are 0.1.1's: sin/cos of the unwrapped relative heading; humans' relative speed is
//! |v_h − v_r| (non-negative), every other entity carries −|v_r| and −ω; walls are split into
//! segments of `wall_segment_size` from their "left" end. One 0.1.1 bug is fixed
//! (docs/fidelity.md): the relative angular speed wraps the heading difference, so it never
//! jumps by ±2π/dt.

use crate::math;
use crate::outputs::OutChunk;
use crate::params::StepParams;
use crate::pipeline::Batch;
use crate::spec::{RECORD, entity, one_hot};
use crate::state::StateChunk;

/// Write the observation of environment `e` and cache the humans' relative headings.
pub fn observation(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    write_observation(p, &mut b.s, &mut b.o, e);
}

/// The robot pose and velocities an observation is relative to.
#[derive(Debug, Clone, Copy)]
struct Frame {
    x: f32,
    y: f32,
    theta: f32,
    sin: f32,
    cos: f32,
    /// Robot world velocity (m/s).
    vx: f32,
    vy: f32,
    /// −|v| and −ω: what non-human records carry.
    neg_speed: f32,
    neg_w: f32,
}

impl Frame {
    fn of(s: &StateChunk, e: usize) -> Self {
        let theta = s.robot_theta[e];
        let (sin, cos) = math::sin_cos(theta);
        let (vx, vy) = super::reward::robot_world_velocity(s, e);
        let (cx, cy) = (s.robot_vx[e], s.robot_vy[e]);
        Self {
            x: s.robot_x[e],
            y: s.robot_y[e],
            theta,
            sin,
            cos,
            vx,
            vy,
            neg_speed: -(cx * cx + cy * cy).sqrt(),
            neg_w: -s.robot_w[e],
        }
    }

    /// World point → robot frame.
    #[inline]
    fn local(&self, x: f32, y: f32) -> (f32, f32) {
        let dx = x - self.x;
        let dy = y - self.y;
        (self.cos * dx + self.sin * dy, self.cos * dy - self.sin * dx)
    }
}

/// Write the full observation row of environment `e` (records past the counts are zeroed) and
/// update the relative-heading cache of its humans.
pub fn write_observation(p: &StepParams, s: &mut StateChunk, o: &mut OutChunk, e: usize) {
    let layout = o.strides.layout;
    let row = &mut o.obs[e * layout.dim..(e + 1) * layout.dim];
    let f = Frame::of(s, e);
    robot_record(p, s, e, &f, &mut row[..layout.robot]);
    let mut counts = [0u32; 5];
    counts[entity::HUMANS] = humans(p, s, e, &f, &mut row[layout.offset[entity::HUMANS]..]);
    counts[entity::LAPTOPS] = laptops(p, s, e, &f, &mut row[layout.offset[entity::LAPTOPS]..]);
    counts[entity::TABLES] = tables(p, s, e, &f, &mut row[layout.offset[entity::TABLES]..]);
    counts[entity::PLANTS] = plants(p, s, e, &f, &mut row[layout.offset[entity::PLANTS]..]);
    if layout.capacity[entity::WALLS] > 0 {
        counts[entity::WALLS] = walls(p, s, e, &f, &mut row[layout.offset[entity::WALLS]..]);
    }
    for (t, &n) in counts.iter().enumerate() {
        let from = layout.offset[t] + n as usize * RECORD;
        let to = layout.offset[t] + layout.capacity[t] * RECORD;
        row[from..to].fill(0.0);
    }
    o.obs_count[e * 5..e * 5 + 5].copy_from_slice(&counts);
}

fn robot_record(p: &StepParams, s: &StateChunk, e: usize, f: &Frame, out: &mut [f32]) {
    out[..6].fill(0.0);
    out[one_hot::ROBOT] = 1.0;
    let (gx, gy) = f.local(s.goal_x[e], s.goal_y[e]);
    out[6] = gx;
    out[7] = gy;
    out[8] = p.robot_radius;
    if p.obs_robot_velocity != 0 {
        out[9] = s.robot_vx[e];
        out[10] = s.robot_vy[e];
        out[11] = s.robot_w[e];
    }
}

/// One non-human record: one-hot, robot-frame position, sin/cos of the relative heading, radius,
/// and the robot's negated speed and angular speed.
#[inline]
fn object_record(out: &mut [f32], kind: usize, f: &Frame, x: f32, y: f32, theta: f32, radius: f32) {
    let (lx, ly) = f.local(x, y);
    let (sn, c) = math::sin_cos(theta - f.theta);
    local_record(out, kind, f, lx, ly, sn, c, radius);
}

/// A non-human record from a robot-frame position (m) and the relative heading's sin and cos.
#[inline]
#[expect(
    clippy::too_many_arguments,
    reason = "one record's fields, written in one place"
)]
fn local_record(
    out: &mut [f32],
    kind: usize,
    f: &Frame,
    lx: f32,
    ly: f32,
    sn: f32,
    c: f32,
    radius: f32,
) {
    let r = record(out);
    *r = [0.0; RECORD];
    r[kind] = 1.0;
    r[6] = lx;
    r[7] = ly;
    r[8] = sn;
    r[9] = c;
    r[10] = radius;
    r[11] = f.neg_speed;
    r[12] = f.neg_w;
}

/// The first record of `out` as a fixed-size array: one bounds check, then plain stores.
#[inline]
fn record(out: &mut [f32]) -> &mut [f32; RECORD] {
    (&mut out[..RECORD])
        .try_into()
        .expect("a slice of RECORD floats")
}

fn humans(p: &StepParams, s: &mut StateChunk, e: usize, f: &Frame, out: &mut [f32]) -> u32 {
    let hb = e * s.strides.humans;
    let n = s.n_humans[e] as usize;
    for k in 0..n {
        let i = hb + k;
        let r = record(&mut out[k * RECORD..]);
        *r = [0.0; RECORD];
        r[one_hot::HUMAN] = 1.0;
        let theta = s.h_theta[i];
        let (lx, ly) = f.local(s.h_x[i], s.h_y[i]);
        let rel = theta - f.theta;
        let (sn, c) = math::sin_cos(rel);
        let (hs, hc) = math::sin_cos(theta);
        let dvx = s.h_vx[i] - f.vx;
        let dvy = s.h_vy[i] - f.vy;
        let wrapped = math::wrap_angle(rel);
        r[6] = lx;
        r[7] = ly;
        r[8] = sn;
        r[9] = c;
        r[10] = p.human_radius;
        r[11] = (dvx * dvx + dvy * dvy).sqrt();
        r[12] = math::wrap_angle(wrapped - s.h_prev_rel_theta[i]) / p.dt;
        r[13] = gaze(p, s.h_x[i], s.h_y[i], hc, hs, f);
        s.h_prev_rel_theta[i] = wrapped;
    }
    n as u32
}

/// 1 if the robot centre, seen from the human (heading cos `hc`, sin `hs`), lies within the gaze
/// cone of half-angle gaze_angle/2.
#[inline]
fn gaze(p: &StepParams, hx: f32, hy: f32, hc: f32, hs: f32, f: &Frame) -> f32 {
    let dx = f.x - hx;
    let dy = f.y - hy;
    let bearing = math::atan2(hc * dy - hs * dx, hc * dx + hs * dy);
    let half = 0.5 * p.gaze_angle;
    if bearing >= -half && bearing <= half {
        1.0
    } else {
        0.0
    }
}

fn laptops(p: &StepParams, s: &StateChunk, e: usize, f: &Frame, out: &mut [f32]) -> u32 {
    let r = s.strides.laptops;
    let radius = circumradius(p.laptop_length, p.laptop_width);
    let (x, y, theta) = (&s.l_x[e * r..], &s.l_y[e * r..], &s.l_theta[e * r..]);
    rectangles(
        out,
        one_hot::LAPTOP,
        f,
        x,
        y,
        theta,
        s.n_laptops[e] as usize,
        radius,
    )
}

fn tables(p: &StepParams, s: &StateChunk, e: usize, f: &Frame, out: &mut [f32]) -> u32 {
    let r = s.strides.tables;
    let radius = circumradius(p.table_length, p.table_width);
    let (x, y, theta) = (&s.t_x[e * r..], &s.t_y[e * r..], &s.t_theta[e * r..]);
    rectangles(
        out,
        one_hot::TABLE,
        f,
        x,
        y,
        theta,
        s.n_tables[e] as usize,
        radius,
    )
}

/// Half the diagonal of a `length` × `width` rectangle (m): the observed radius of tables and laptops.
#[inline]
fn circumradius(length: f32, width: f32) -> f32 {
    (0.25 * length * length + 0.25 * width * width).sqrt()
}

/// Records of the first `n` rectangles of one kind (centres and headings in world coordinates).
#[expect(
    clippy::too_many_arguments,
    reason = "one entity kind's columns and constants"
)]
fn rectangles(
    out: &mut [f32],
    kind: usize,
    f: &Frame,
    x: &[f32],
    y: &[f32],
    theta: &[f32],
    n: usize,
    radius: f32,
) -> u32 {
    for k in 0..n {
        object_record(
            &mut out[k * RECORD..],
            kind,
            f,
            x[k],
            y[k],
            theta[k],
            radius,
        );
    }
    n as u32
}

fn plants(p: &StepParams, s: &StateChunk, e: usize, f: &Frame, out: &mut [f32]) -> u32 {
    let pb = e * s.strides.plants;
    let n = s.n_plants[e] as usize;
    for k in 0..n {
        let i = pb + k;
        object_record(
            &mut out[k * RECORD..],
            one_hot::PLANT,
            f,
            s.p_x[i],
            s.p_y[i],
            0.0,
            p.plant_radius,
        );
    }
    n as u32
}

/// Wall segments: for each wall, floor(L/s) segments of length s from its left end
/// (centre − L/2·(cos θ, sin θ)), then one remainder segment if L is not a multiple of s. The
/// left end and the wall direction are brought into the robot frame once per wall.
fn walls(p: &StepParams, s: &StateChunk, e: usize, f: &Frame, out: &mut [f32]) -> u32 {
    let wb = e * s.strides.walls;
    let step = p.wall_segment_size;
    let mut k = 0usize;
    for w in wb..wb + s.n_walls[e] as usize {
        let length = s.w_length[w];
        let (wc, ws) = (s.w_cos[w], s.w_sin[w]);
        let (lx, ly) = f.local(s.w_x[w] - 0.5 * length * wc, s.w_y[w] - 0.5 * length * ws);
        let (dx, dy) = (f.cos * wc + f.sin * ws, f.cos * ws - f.sin * wc);
        let (sn, c) = math::sin_cos(s.w_theta[w] - f.theta);
        let (full, rest) = crate::scenario::layout::segments(length, step);
        // Every segment of a wall shares its record but for the position: write the template,
        // then the two coordinates.
        let mut template = [0.0f32; RECORD];
        local_record(&mut template, one_hot::WALL, f, 0.0, 0.0, sn, c, 0.5 * step);
        for j in 0..full {
            let along = (j as f32 + 0.5) * step;
            let r = record(&mut out[k * RECORD..]);
            *r = template;
            r[6] = lx + along * dx;
            r[7] = ly + along * dy;
            k += 1;
        }
        if rest > 0.0 {
            let along = full as f32 * step + 0.5 * rest;
            template[10] = 0.5 * rest;
            let r = record(&mut out[k * RECORD..]);
            *r = template;
            r[6] = lx + along * dx;
            r[7] = ly + along * dy;
            k += 1;
        }
    }
    k as u32
}
