//! Stage `contacts` (docs/spec.md 4.6): after all motion, a human that touches a plant, wall, table
//! or free laptop is pushed out by an MPE-style soft contact force: it turns to the force
//! direction, takes speed min(|F|·dt, max speed) and moves once more. Non-wall objects count as
//! discs (tables and laptops by their circumradius); against a wall the obstacle is the human's
//! mirror image across the wall face. A lone static human is never moved nor turned but takes the
//! push's speed, as in 0.1.1, whose `Human.update` and `update_orientation` return early for a
//! static human while the speed assignment does not. The robot is never pushed. Whether a human
//! touches an object is decided with discs shaped as `[model] contact_shape` says (0.1.1: 64-gons),
//! an overlap of at most [`CONTACT_SLOP`] not counting; the force formula stays the one of exact
//! discs.

use crate::geometry::{Disc, Rect, disc_disc_as, disc_rect_as};
use crate::math;
use crate::params::StepParams;
use crate::state::{NONE, StateChunk, role};

use super::Batch;

/// Softness of the contact (m), MPE's `contact_margin`.
pub const MARGIN: f32 = 1e-3;
/// Stiffness of the contact, MPE's `contact_force`.
pub const STIFFNESS: f32 = 100.0;
/// Overlap (m) that does not count as a contact: the f32 rounding of a position update. ORCA
/// stops a walker exactly at an obstacle's surface (RVO2's obstacle constraint), and may hold it
/// there for many steps; 0.1.1 moves it in f64 and leaves it outside by ~1e-8 m, socnav's f32
/// update (half an ulp: up to 9.5e-7 m at 16 m from the origin) leaves it as often a few 1e-7 m
/// inside, and would push it out every step where 0.1.1 lets it slide (seen on episodes recorded
/// from 0.1.1 beyond the published ones). Real contacts, a walker or a group member walking into
/// an object, overlap by millimetres.
pub const CONTACT_SLOP: f32 = 1e-6;

/// Resolve the contacts of every human of environment `e`.
pub fn contacts(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    let s = &mut b.s;
    let hb = e * s.strides.humans;
    for i in hb..hb + s.n_humans[e] as usize {
        push_out(p, s, e, i);
    }
}

fn push_out(p: &StepParams, s: &mut StateChunk, e: usize, i: usize) {
    let r = p.human_radius;
    let pb = e * s.strides.plants;
    for k in pb..pb + s.n_plants[e] as usize {
        let plant = Disc {
            x: s.p_x[k],
            y: s.p_y[k],
            r: p.plant_radius,
        };
        if disc_disc_as(p.contact_shape, &human(p, s, i), &plant) {
            let (dx, dy) = (s.h_x[i] - plant.x, s.h_y[i] - plant.y);
            push(p, s, i, dx, dy, r + plant.r);
        }
    }
    for w in 0..s.n_walls[e] as usize {
        let wall = super::world::wall_rect(p, s, e, w);
        if disc_rect_as(p.contact_shape, &human(p, s, i), &wall) {
            let (dx, dy) = mirror_delta(&wall, s.h_x[i], s.h_y[i]);
            push(p, s, i, dx, dy, 2.0 * r);
        }
    }
    for t in 0..s.n_tables[e] as usize {
        let table = super::world::table_rect(p, s, e, t);
        push_from_rect(p, s, i, &table);
    }
    let lb = e * s.strides.laptops;
    for l in 0..s.n_laptops[e] as usize {
        if s.l_user[lb + l] == NONE {
            let laptop = super::world::laptop_rect(p, s, e, l);
            push_from_rect(p, s, i, &laptop);
        }
    }
}

/// The human's disc for the contact decision: its radius less [`CONTACT_SLOP`].
#[inline]
fn human(p: &StepParams, s: &StateChunk, i: usize) -> Disc {
    Disc {
        x: s.h_x[i],
        y: s.h_y[i],
        r: p.human_radius - CONTACT_SLOP,
    }
}

fn push_from_rect(p: &StepParams, s: &mut StateChunk, i: usize, rect: &Rect) {
    if disc_rect_as(p.contact_shape, &human(p, s, i), rect) {
        let (dx, dy) = (s.h_x[i] - rect.x, s.h_y[i] - rect.y);
        push(p, s, i, dx, dy, p.human_radius + rect.circumradius());
    }
}

/// Human centre minus its mirror image across the wall face on the human's side.
fn mirror_delta(wall: &Rect, x: f32, y: f32) -> (f32, f32) {
    let (_, ly) = wall.to_local(x, y);
    let face = if ly >= 0.0 { wall.hw } else { -wall.hw };
    let across = 2.0 * (ly - face);
    (-wall.s * across, wall.c * across)
}

/// Apply the contact force for separation vector (dx, dy) and contact distance `reach` (m): the
/// human turns to the force, takes its speed and moves, except a lone static human, which only
/// takes the speed (its cached velocity follows along its unchanged heading).
fn push(p: &StepParams, s: &mut StateChunk, i: usize, dx: f32, dy: f32, reach: f32) {
    let dist = (dx * dx + dy * dy).sqrt();
    if dist <= 0.0 {
        return;
    }
    let penetration = MARGIN * math::softplus(-(dist - reach) / MARGIN);
    let fx = STIFFNESS * dx / dist * penetration;
    let fy = STIFFNESS * dy / dist * penetration;
    let movable = s.h_role[i] != role::STATIC;
    let theta = if movable {
        math::atan2(fy, fx)
    } else {
        s.h_theta[i]
    };
    let speed = ((fx * fx + fy * fy).sqrt() * p.dt).min(p.human_max_speed);
    let (sn, c) = math::sin_cos(theta);
    s.h_theta[i] = theta;
    s.h_speed[i] = speed;
    s.h_vx[i] = speed * c;
    s.h_vy[i] = speed * sn;
    if movable {
        s.h_x[i] += speed * p.dt * c;
        s.h_y[i] += speed * p.dt * sn;
    }
}
