//! Stage `robot_motion` (docs/spec.md 4.1 steps 2-3): scale the action to a physical command and
//! move the robot by semi-implicit Euler (rotate first, then translate along the new heading). The
//! robot is never pushed: a collision just ends the episode.

use crate::math::{self, FRAC_PI_2};
use crate::params::StepParams;
use crate::state::StateChunk;

use super::Batch;

/// The physical command (v_x, v_y in m/s, robot frame; ω in rad/s) of an action in [-1, 1]³:
/// each component scaled, then clipped to its maximum; the lateral one is 0 for diff-drive.
#[inline]
pub fn command(p: &StepParams, a: &[f32]) -> (f32, f32, f32) {
    let v = p.robot_max_speed;
    let w = p.robot_max_rotation;
    let vx = (a[0] * v).clamp(-v, v);
    let vy = if p.holonomic != 0 {
        (a[1] * v).clamp(-v, v)
    } else {
        0.0
    };
    let wz = (a[2] * w).clamp(-w, w);
    (vx, vy, wz)
}

/// A pose (m, m, rad) after one step, with the world-frame velocity (m/s) of the command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moved {
    /// x (m).
    pub x: f32,
    /// y (m).
    pub y: f32,
    /// Heading (rad), wrapped to (-π, π].
    pub theta: f32,
    /// World-frame velocity x (m/s): v_x cos θ + v_y cos(θ + π/2).
    pub vx: f32,
    /// World-frame velocity y (m/s).
    pub vy: f32,
}

/// Integrate a pose (m, m, rad) by one step of the command: θ ← wrap(θ + ω dt), then
/// x ← x + v_x cos θ dt + v_y cos(θ + π/2) dt (likewise y), in 0.1.1's operation order. Without a
/// lateral command the θ + π/2 terms vanish and are not computed.
#[inline]
pub fn integrate(dt: f32, x: f32, y: f32, theta: f32, vx: f32, vy: f32, w: f32) -> Moved {
    let theta = math::wrap_angle(theta + w * dt);
    let (s, c) = math::sin_cos(theta);
    if vy == 0.0 {
        return Moved {
            x: x + vx * c * dt,
            y: y + vx * s * dt,
            theta,
            vx: vx * c,
            vy: vx * s,
        };
    }
    let (s2, c2) = math::sin_cos(theta + FRAC_PI_2);
    Moved {
        x: x + vx * c * dt + vy * c2 * dt,
        y: y + vx * s * dt + vy * s2 * dt,
        theta,
        vx: vx * c + vy * c2,
        vy: vx * s + vy * s2,
    }
}

/// The world-frame velocity (m/s) of command (v_x, v_y) at heading θ, as [`integrate`] computes it.
#[inline]
pub fn world_velocity(theta: f32, vx: f32, vy: f32) -> (f32, f32) {
    let m = integrate(0.0, 0.0, 0.0, theta, vx, vy, 0.0);
    (m.vx, m.vy)
}

/// The robot's world-frame velocity (m/s): its command turned by its heading, computed with the
/// motion (`robot_wvx`, `robot_wvy`).
#[inline]
pub fn robot_world_velocity(s: &StateChunk, e: usize) -> (f32, f32) {
    (s.robot_wvx[e], s.robot_wvy[e])
}

/// Apply this step's action to the robot.
pub fn robot_motion(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    let (vx, vy, w) = command(p, &b.actions[3 * e..3 * e + 3]);
    let s = &mut b.s;
    s.robot_vx[e] = vx;
    s.robot_vy[e] = vy;
    s.robot_w[e] = w;
    let m = integrate(
        p.dt,
        s.robot_x[e],
        s.robot_y[e],
        s.robot_theta[e],
        vx,
        vy,
        w,
    );
    s.robot_x[e] = m.x;
    s.robot_y[e] = m.y;
    s.robot_theta[e] = m.theta;
    s.robot_wvx[e] = m.vx;
    s.robot_wvy[e] = m.vy;
}
