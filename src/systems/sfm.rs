//! SocNavGym 0.1.1's one-shot social force model (docs/spec.md 4.3, docs/spec.md orca-sfm 3.5): the
//! velocity of a lone walker is recomputed from scratch every step as (f/mass)·dt, capped at the
//! human speed, with f = w·(desired + Σ obstacle + Σ pedestrian forces), w = 1/√3. There is no
//! velocity state. Only the obstacles and humans in the walker's field of view push it
//! (`perception.rs`); the robot, when the walker avoids it this step, pushes it seen or not (as in
//! 0.1.1).

use crate::geometry::{Disc, Shape};
use crate::math;
use crate::params::StepParams;
use crate::state::{StateChunk, group_kind, role};

use super::perception::{self, View};

/// Weight of each force group (0.1.1: 1/√3 each).
pub const W: f32 = 0.577_350_26;

/// Per-episode SFM parameters of an environment.
#[derive(Debug, Clone, Copy)]
struct Params {
    r0: f32,
    gamma: f32,
    n: f32,
    n_prime: f32,
    lambda: f32,
}

/// The SFM velocity (m/s, world frame) of human slot `i` of environment `e`; `robot` says whether
/// this human takes the robot into account this step, `view` what it sees (`None`: everything).
pub fn velocity(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    i: usize,
    robot: bool,
    view: Option<&View>,
) -> (f32, f32) {
    let sp = Params {
        r0: s.sfm_r0[e],
        gamma: s.sfm_gamma[e],
        n: s.sfm_n[e],
        n_prime: s.sfm_n_prime[e],
        lambda: s.sfm_lambda[e],
    };
    let (x, y) = (s.h_x[i], s.h_y[i]);
    let (dx, dy) = unit(s.h_goal_x[i] - x, s.h_goal_y[i] - y);
    let (mut fdx, mut fdy) = (p.human_max_speed * dx, p.human_max_speed * dy);
    let obstacles = Obstacles {
        p,
        s,
        e,
        x,
        y,
        r0: sp.r0,
        robot,
        view,
    };
    let (fox, foy, top) = obstacles.forces(0.0);
    if !(fox.is_finite() && foy.is_finite()) {
        return overwhelmed(p, &obstacles, top);
    }
    let (fpx, fpy) = pedestrian_forces(p, s, e, i, &sp, view);
    fdx = W * fdx + W * fox + W * fpx;
    fdy = W * fdy + W * foy + W * fpy;
    // mass 1: v = f·dt, capped at the human speed.
    let (vx, vy) = (fdx * p.dt, fdy * p.dt);
    let v = length(vx, vy);
    if v > p.human_max_speed {
        let k = p.human_max_speed / v;
        (vx * k, vy * k)
    } else {
        (vx, vy)
    }
}

/// What the obstacles' push on a walker at (x, y) (m) depends on.
struct Obstacles<'a> {
    p: &'a StepParams,
    s: &'a StateChunk<'a>,
    e: usize,
    x: f32,
    y: f32,
    r0: f32,
    robot: bool,
    view: Option<&'a View>,
}

impl Obstacles<'_> {
    /// Σ exp(−gap / r0 − scale) · unit(walker − nearest point) over the obstacles the walker sees,
    /// and the largest exponent −gap / r0 of them (f32::MIN without any). `scale` 0 gives the
    /// obstacle force of 0.1.1 (x − 0 is x, so its bits too).
    fn forces(&self, scale: f32) -> (f32, f32, f32) {
        let (p, s, e, x, y, view) = (self.p, self.s, self.e, self.x, self.y, self.view);
        let (mut fox, mut foy, mut top) = (0.0f32, 0.0f32, f32::MIN);
        let mut obstacle = |ox: f32, oy: f32, surface_gap: f32| {
            let (ux, uy) = unit(x - ox, y - oy);
            let a = -surface_gap / self.r0;
            let m = math::exp(a - scale);
            fox += m * ux;
            foy += m * uy;
            top = top.max(a);
        };
        let r = p.human_radius;
        let disc_gap = |ox: f32, oy: f32, ro: f32| length(x - ox, y - oy) - ro - r;
        // Discs push from their centre, rectangles from their nearest point; unseen ones not at all.
        let mut push = |shape: Shape| {
            if !perception::sees(view, &shape) {
                return;
            }
            match shape {
                Shape::Disc(d) => obstacle(d.x, d.y, disc_gap(d.x, d.y, d.r)),
                Shape::Rect(rc) => {
                    let (qx, qy) = rc.nearest_point(x, y);
                    obstacle(qx, qy, length(x - qx, y - qy) - r);
                }
            }
        };
        let pb = e * s.strides.plants;
        for k in pb..pb + s.n_plants[e] as usize {
            push(Shape::Disc(Disc {
                x: s.p_x[k],
                y: s.p_y[k],
                r: p.plant_radius,
            }));
        }
        for w in 0..s.n_walls[e] as usize {
            push(Shape::Rect(super::world::wall_rect(p, s, e, w)));
        }
        for t in 0..s.n_tables[e] as usize {
            push(Shape::Rect(super::world::table_rect(p, s, e, t)));
        }
        let lb = e * s.strides.laptops;
        for l in 0..s.n_laptops[e] as usize {
            if s.l_user[lb + l] == crate::state::NONE {
                push(Shape::Rect(super::world::laptop_rect(p, s, e, l)));
            }
        }
        let gb = e * s.strides.groups;
        for g in gb..gb + s.n_groups[e] as usize {
            if s.g_kind[g] == group_kind::STANDING {
                push(Shape::Disc(perception::group_disc(p, s, g)));
            }
        }
        if self.robot {
            let (rx, ry) = (s.robot_x[e], s.robot_y[e]);
            obstacle(rx, ry, disc_gap(rx, ry, p.robot_radius));
        }
        (fox, foy, top)
    }
}

/// The velocity (m/s) of a walker whose obstacle force overflows f32 (an exponent −gap / r0
/// above 88: a tiny drawn r0, |0.05 + 0.01 N| m, and a walker deep against an obstacle). 0.1.1
/// computes in f64, where the force is finite up to an exponent of 709 and so large that the
/// goal and pedestrian terms vanish beside it: the capped velocity is the speed limit along the
/// obstacle force. Here that direction comes from the forces rescaled by exp(−top), top the
/// largest exponent, which no term exceeds. (Beyond 709 0.1.1's velocity is NaN; socnav's stays
/// this one. A walker pushed exactly equally from opposite sides stands still.)
fn overwhelmed(p: &StepParams, obstacles: &Obstacles<'_>, top: f32) -> (f32, f32) {
    let (sx, sy, _) = obstacles.forces(top);
    let (ux, uy) = unit(sx, sy);
    (p.human_max_speed * ux, p.human_max_speed * uy)
}

/// Σ f_ij over the lone humans, moving-group members and laptop users `view` sees (standing-group
/// members are obstacles through their group's disc).
fn pedestrian_forces(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    i: usize,
    sp: &Params,
    view: Option<&View>,
) -> (f32, f32) {
    let hb = e * s.strides.humans;
    let (xi, yi) = (s.h_x[i], s.h_y[i]);
    let (vix, viy) = (s.h_vx[i], s.h_vy[i]);
    let (mut fx, mut fy) = (0.0f32, 0.0f32);
    for j in hb..hb + s.n_humans[e] as usize {
        if j == i
            || s.h_role[j] == role::STANDING_GROUP
            || !perception::sees_human(view, p, s, e, j)
        {
            continue;
        }
        let (vjx, vjy) = (s.h_vx[j], s.h_vy[j]);
        let (ex, ey) = unit(s.h_x[j] - xi, s.h_y[j] - yi);
        let dx = sp.lambda * (vjx - vix) + ex;
        let dy = sp.lambda * (vjy - viy) + ey;
        let d_len = length(dx, dy);
        let b = sp.gamma * d_len;
        let (tx, ty) = if d_len > 0.0 {
            (dx / d_len, dy / d_len)
        } else {
            (0.0, 0.0)
        };
        let theta = math::acos((ex * tx + ey * ty).clamp(-1.0, 1.0));
        let (nx, ny) = (-ey, ex);
        let d = length(xi - s.h_x[j], yi - s.h_y[j]);
        if d == 0.0 && b == 0.0 {
            // Two walkers at one point with one velocity: no direction to push along (e, t and
            // n are zero) and exp(-0 / 0) is NaN, in 0.1.1's f64 too; the pair exerts no force.
            continue;
        }
        let m = -math::exp(-d / b);
        let a1 = sp.n_prime * b * theta;
        let a2 = sp.n * b * theta;
        let k1 = math::exp(-(a1 * a1));
        let k2 = math::exp(-(a2 * a2));
        fx += m * (k1 * tx + k2 * nx);
        fy += m * (k1 * ty + k2 * ny);
    }
    (fx, fy)
}

#[inline]
fn length(x: f32, y: f32) -> f32 {
    (x * x + y * y).sqrt()
}

/// Unit vector of (x, y); zero for the zero vector.
#[inline]
fn unit(x: f32, y: f32) -> (f32, f32) {
    let l = length(x, y);
    if l > 0.0 { (x / l, y / l) } else { (0.0, 0.0) }
}
