//! Stage `shadow_robot` (docs/spec.md 8.2): the reference robot behind STL and SPL. A copy of the
//! robot made at reset drives to the same goal, every step (until it collides or arrives) by the
//! ORCA velocity of a fresh simulator that holds every lone human and moving group, converted to
//! the robot's kinematics. It "collides" when it touches a human or an object (0.1.1 tests groups
//! and laptop users against the real robot instead; fixed, see docs/fidelity.md), with discs shaped
//! as `[model] contact_shape` says. As in 0.1.1 it moves before the humans but is tested against
//! them after they moved ([`shadow_outcome`]).

use crate::geometry::Disc;
use crate::math;
use crate::params::StepParams;
use crate::state::StateChunk;

use super::Batch;
use super::orca_world::{self, Others};

/// Advance the shadow robot of environment `e`.
pub fn shadow_robot(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    let s = &mut b.s;
    if s.stepping[e] == 0 || s.shadow_collided[e] != 0 || s.shadow_reached[e] != 0 {
        return;
    }
    let (x, y, theta) = (s.shadow_x[e], s.shadow_y[e], s.shadow_theta[e]);
    let pref = orca_world::preferred(x, y, s.goal_x[e], s.goal_y[e], p.robot_max_speed);
    let agent = orca_world::agent(s, e, [x, y], [0.0, 0.0], pref, p.human_radius);
    let others = Others {
        skip_human: None,
        skip_group: None,
        robot: false,
        // The shadow robot sees everything (0.1.1 adds every entity to its simulator).
        view: None,
    };
    let v = orca_world::with_world(|w| w.velocity(p, s, e, &agent, others));
    let (vx, vy, w) = command_from_velocity(p, theta, v[0], v[1]);
    let m = super::robot_motion::integrate(p.dt, x, y, theta, vx, vy, w);
    s.shadow_x[e] = m.x;
    s.shadow_y[e] = m.y;
    s.shadow_theta[e] = m.theta;
    s.shadow_vx[e] = vx;
    s.shadow_vy[e] = vy;
    s.shadow_w[e] = w;
    s.shadow_path_length[e] += (vx * vx + vy * vy).sqrt() * p.dt;
}

/// Whether the shadow robot collided or arrived, decided with the rest of the step's outcome
/// (stage `termination`), i.e. against the humans where they stand after this step's motion.
pub fn shadow_outcome(p: &StepParams, s: &mut StateChunk, e: usize) {
    if s.shadow_collided[e] != 0 || s.shadow_reached[e] != 0 {
        return;
    }
    let (x, y) = (s.shadow_x[e], s.shadow_y[e]);
    let touch = super::world::touches(
        p,
        s,
        e,
        &Disc {
            x,
            y,
            r: p.robot_radius,
        },
    );
    if touch.human || touch.object {
        s.shadow_collided[e] = 1;
    }
    let (dx, dy) = (s.goal_x[e] - x, s.goal_y[e] - y);
    if (dx * dx + dy * dy).sqrt() < p.robot_radius + p.goal_radius {
        s.shadow_reached[e] = 1;
        s.shadow_reach_tick[e] = s.tick[e];
    }
}

/// A world-frame velocity (m/s) as a robot command: diff-drive drives at |v| and turns by the
/// (unwrapped) heading error per step; holonomic drives v rotated into the robot frame. Each
/// component is clipped to its maximum.
pub fn command_from_velocity(p: &StepParams, theta: f32, vx: f32, vy: f32) -> (f32, f32, f32) {
    let v = p.robot_max_speed;
    let wmax = p.robot_max_rotation;
    let w = ((math::atan2(vy, vx) - theta) / p.dt).clamp(-wmax, wmax);
    if p.holonomic != 0 {
        let (sn, c) = math::sin_cos(theta);
        let fx = c * vx + sn * vy;
        let fy = c * vy - sn * vx;
        (fx.clamp(-v, v), fy.clamp(-v, v), w)
    } else {
        ((vx * vx + vy * vy).sqrt().clamp(-v, v), 0.0, w)
    }
}
