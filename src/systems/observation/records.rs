//! The records of one environment, in the robot or the world frame, keeping only what the sensor
//! sees (compacted to the front of each block, order preserved). Each writer returns the number of
//! records it wrote; the caller zeroes the rest of the block.
//!
//! World frame (0.1.1's `WorldFrameObservations`): positions (m) and headings in the world frame;
//! indices 11-12 hold a human's world velocity (m/s) and 0, 0 for every other entity, walls
//! included; radius and gaze are as in the robot frame.

use super::Frame;
use crate::math;
use crate::params::StepParams;
use crate::spec::{RECORD, one_hot};
use crate::state::StateChunk;

/// The robot record: robot frame `[one-hot, goal x, goal y, radius]` (+ the command v_x, v_y, ω
/// with `robot_velocity`); world frame `[one-hot, goal x, goal y, x, y, sin θ, cos θ, v_x, v_y,
/// ω, radius]` with the command in the robot frame, as 0.1.1's wrapper.
pub(super) fn robot<const W: bool, const P: bool>(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    out: &mut [f32],
) {
    out[..6].fill(0.0);
    out[one_hot::ROBOT] = 1.0;
    if W {
        out[6] = s.goal_x[e];
        out[7] = s.goal_y[e];
        out[8] = f.x;
        out[9] = f.y;
        out[10] = f.sin;
        out[11] = f.cos;
        out[12] = s.robot_vx[e];
        out[13] = s.robot_vy[e];
        out[14] = s.robot_w[e];
        out[15] = p.robot_radius;
        return;
    }
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

/// The first record of `out` as a fixed-size array: one bounds check, then plain stores.
#[inline]
#[expect(
    clippy::expect_used,
    reason = "callers pass a record slot of RECORD floats"
)]
fn record(out: &mut [f32]) -> &mut [f32; RECORD] {
    (&mut out[..RECORD])
        .try_into()
        .expect("a slice of RECORD floats")
}

/// A non-human record: one-hot, written position (m), sin and cos of the written heading,
/// radius (m), and the frame's indices 11-12 for objects.
#[inline]
fn object_record<const W: bool, const P: bool>(
    out: &mut [f32; RECORD],
    kind: usize,
    f: &Frame<W, P>,
    pos: (f32, f32),
    sc: (f32, f32),
    radius: f32,
) {
    *out = [0.0; RECORD];
    out[kind] = 1.0;
    out[6] = pos.0;
    out[7] = pos.1;
    out[8] = sc.0;
    out[9] = sc.1;
    out[10] = radius;
    out[11] = f.object_v;
    out[12] = f.object_w;
}

/// Human records. The relative-heading cache is updated for every human, seen or not, so that a
/// human coming into view reports the change since the previous step.
pub(super) fn humans<const W: bool, const P: bool>(
    p: &StepParams,
    s: &mut StateChunk,
    e: usize,
    f: &Frame<W, P>,
    out: &mut [f32],
) -> u32 {
    let hb = e * s.strides.humans;
    let mut k = 0;
    for i in hb..hb + s.n_humans[e] as usize {
        let theta = s.h_theta[i];
        let rel = theta - f.theta;
        let wrapped = math::wrap_angle(rel);
        let prev = s.h_prev_rel_theta[i];
        s.h_prev_rel_theta[i] = wrapped;
        let (x, y) = (s.h_x[i], s.h_y[i]);
        let (lx, ly) = f.local(x, y);
        if !f.sees(lx, ly) {
            continue;
        }
        let r = record(&mut out[k * RECORD..]);
        k += 1;
        *r = [0.0; RECORD];
        r[one_hot::HUMAN] = 1.0;
        let (hs, hc) = math::sin_cos(theta);
        r[10] = p.human_radius;
        r[13] = gaze(p, x, y, hc, hs, f);
        if W {
            r[6] = x;
            r[7] = y;
            r[8] = hs;
            r[9] = hc;
            r[11] = s.h_vx[i];
            r[12] = s.h_vy[i];
        } else {
            let (sn, c) = math::sin_cos(rel);
            let dvx = s.h_vx[i] - f.vx;
            let dvy = s.h_vy[i] - f.vy;
            r[6] = lx;
            r[7] = ly;
            r[8] = sn;
            r[9] = c;
            r[11] = (dvx * dvx + dvy * dvy).sqrt();
            r[12] = math::wrap_angle(wrapped - prev) / p.dt;
        }
    }
    k as u32
}

/// 1 if the robot centre, seen from the human (heading cos `hc`, sin `hs`), lies within the gaze
/// cone of half-angle gaze_angle/2.
#[inline]
fn gaze<const W: bool, const P: bool>(
    p: &StepParams,
    hx: f32,
    hy: f32,
    hc: f32,
    hs: f32,
    f: &Frame<W, P>,
) -> f32 {
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

/// Laptop records.
pub(super) fn laptops<const W: bool, const P: bool>(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    out: &mut [f32],
) -> u32 {
    let r = s.strides.laptops;
    let n = s.n_laptops[e] as usize;
    let columns = (&s.l_x[e * r..], &s.l_y[e * r..], &s.l_theta[e * r..]);
    let radius = circumradius(p.laptop_length, p.laptop_width);
    rectangles(out, one_hot::LAPTOP, f, columns, n, radius)
}

/// Table records.
pub(super) fn tables<const W: bool, const P: bool>(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    out: &mut [f32],
) -> u32 {
    let r = s.strides.tables;
    let n = s.n_tables[e] as usize;
    let columns = (&s.t_x[e * r..], &s.t_y[e * r..], &s.t_theta[e * r..]);
    let radius = circumradius(p.table_length, p.table_width);
    rectangles(out, one_hot::TABLE, f, columns, n, radius)
}

/// Half the diagonal of a `length` × `width` rectangle (m): the observed radius of tables and laptops.
#[inline]
fn circumradius(length: f32, width: f32) -> f32 {
    (0.25 * length * length + 0.25 * width * width).sqrt()
}

/// Records of the first `n` rectangles of one kind (centre x, y and heading columns, world frame).
fn rectangles<const W: bool, const P: bool>(
    out: &mut [f32],
    kind: usize,
    f: &Frame<W, P>,
    (x, y, theta): (&[f32], &[f32], &[f32]),
    n: usize,
    radius: f32,
) -> u32 {
    let mut k = 0;
    for j in 0..n {
        let (lx, ly) = f.local(x[j], y[j]);
        if !f.sees(lx, ly) {
            continue;
        }
        let pos = f.written(x[j], y[j], lx, ly);
        let sc = math::sin_cos(theta[j] - f.ref_theta);
        object_record(record(&mut out[k * RECORD..]), kind, f, pos, sc, radius);
        k += 1;
    }
    k as u32
}

/// Plant records (plants have heading 0).
pub(super) fn plants<const W: bool, const P: bool>(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    out: &mut [f32],
) -> u32 {
    let pb = e * s.strides.plants;
    let mut k = 0;
    for i in pb..pb + s.n_plants[e] as usize {
        let (lx, ly) = f.local(s.p_x[i], s.p_y[i]);
        if !f.sees(lx, ly) {
            continue;
        }
        let pos = f.written(s.p_x[i], s.p_y[i], lx, ly);
        let sc = math::sin_cos(0.0 - f.ref_theta);
        object_record(
            record(&mut out[k * RECORD..]),
            one_hot::PLANT,
            f,
            pos,
            sc,
            p.plant_radius,
        );
        k += 1;
    }
    k as u32
}

/// Wall segments: for each wall, floor(L/s) segments of length s from its left end
/// (centre − L/2·(cos θ, sin θ)), then one remainder segment if L is not a multiple of s. The
/// left end and the wall direction are brought into the robot frame once per wall; a segment's
/// visibility is decided at its centre.
pub(super) fn walls<const W: bool, const P: bool>(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    out: &mut [f32],
) -> u32 {
    let wb = e * s.strides.walls;
    let step = p.wall_segment_size;
    let mut k = 0usize;
    for w in wb..wb + s.n_walls[e] as usize {
        let length = s.w_length[w];
        let (wc, ws) = (s.w_cos[w], s.w_sin[w]);
        // The left end and the direction along the wall, in the world and in the robot frame.
        let (x0, y0) = (s.w_x[w] - 0.5 * length * wc, s.w_y[w] - 0.5 * length * ws);
        let (lx, ly) = f.local(x0, y0);
        let (dx, dy) = (f.cos * wc + f.sin * ws, f.cos * ws - f.sin * wc);
        let line = Line {
            local: [lx, ly, dx, dy],
            written: if W {
                [x0, y0, wc, ws]
            } else {
                [lx, ly, dx, dy]
            },
        };
        let sc = math::sin_cos(s.w_theta[w] - f.ref_theta);
        let (full, rest) = crate::room::segments(length, step);
        // Every segment of a wall shares its record but for the position and the remainder's
        // radius: write the template, then the two coordinates.
        let mut template = [0.0f32; RECORD];
        object_record(&mut template, one_hot::WALL, f, (0.0, 0.0), sc, 0.5 * step);
        for j in 0..full {
            k += segment(out, k, f, &template, &line, (j as f32 + 0.5) * step);
        }
        if rest > 0.0 {
            template[10] = 0.5 * rest;
            k += segment(out, k, f, &template, &line, full as f32 * step + 0.5 * rest);
        }
    }
    k as u32
}

/// A wall's left end and unit direction `[x, y, dx, dy]`, in the robot frame (for the sensor) and
/// in the written frame.
struct Line {
    local: [f32; 4],
    written: [f32; 4],
}

/// Write the segment centred `along` metres from the wall's left end as record `k`, if the sensor
/// sees it; returns the number of records written (0 or 1).
#[inline]
fn segment<const W: bool, const P: bool>(
    out: &mut [f32],
    k: usize,
    f: &Frame<W, P>,
    template: &[f32; RECORD],
    line: &Line,
    along: f32,
) -> usize {
    if P {
        let [lx, ly, dx, dy] = line.local;
        if !f.sensor.within(lx + along * dx, ly + along * dy) {
            return 0;
        }
    }
    let [x, y, dx, dy] = line.written;
    let r = record(&mut out[k * RECORD..]);
    *r = *template;
    r[6] = x + along * dx;
    r[7] = y + along * dy;
    1
}
