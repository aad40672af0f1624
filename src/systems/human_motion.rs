//! Stage `human_motion` (docs/spec.md 4.1 step 6, 4.2-4.3): each lone walker, in slot order,
//! chooses a velocity with its policy (ORCA or SFM) and moves at once, so later walkers see it
//! where it now is (0.1.1 updates them one after another). Speeds below the threshold become 0
//! (except for walkers heading to a forming crowd); the heading always follows the velocity.
//! Whether a walker takes the robot into account is drawn every step with `prob_to_avoid_robot`.
//! Both policies see only what lies in the walker's field of view (`perception.rs`; everything at
//! 0.1.1's 2π).

use crate::math;
use crate::params::StepParams;
use crate::state::{StateChunk, policy};

use super::Batch;
use super::orca_world::{self, Others};
use super::perception::View;

/// RNG stream kind of the per-step "does this human avoid the robot" draws (`sub` = tick).
pub const STREAM_AVOID_ROBOT: u32 = 3;

/// Move the lone walkers of environment `e`.
pub fn human_motion(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    let s = &mut b.s;
    let mut rng = super::LazyStream::new(s, e, STREAM_AVOID_ROBOT);
    let first = e * s.strides.humans + s.n_static[e] as usize;
    for i in first..first + s.n_dynamic[e] as usize {
        // Nothing to draw when no walker avoids the robot (every paper config).
        let avoid_robot = p.prob_avoid_robot > 0.0 && rng.get().chance(p.prob_avoid_robot);
        let view = View::of_human(p, s, i);
        let (vx, vy) = if s.h_policy[i] == policy::ORCA {
            orca_velocity(p, s, e, i, avoid_robot, view)
        } else {
            super::sfm::velocity(p, s, e, i, avoid_robot, view.as_ref())
        };
        walk(p, s, i, vx, vy);
    }
}

/// The ORCA velocity (m/s) of lone walker `i`: itself at rest (or at its velocity) wanting to go
/// to its goal at the human speed, in a fresh simulator with the other lone humans, the moving
/// groups and, if it avoids it, the robot; of the humans, groups and obstacles only those in
/// `view` (`None`: all).
fn orca_velocity(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    i: usize,
    avoid_robot: bool,
    view: Option<View>,
) -> (f32, f32) {
    let (x, y) = (s.h_x[i], s.h_y[i]);
    let pref = orca_world::preferred(x, y, s.h_goal_x[i], s.h_goal_y[i], p.human_max_speed);
    let vel = if p.orca_actual_velocity != 0 {
        [s.h_vx[i], s.h_vy[i]]
    } else {
        [0.0, 0.0]
    };
    let agent = orca_world::agent(s, e, [x, y], vel, pref, p.human_radius);
    let others = Others {
        skip_human: Some(i),
        skip_group: None,
        robot: avoid_robot,
        view,
    };
    let v = orca_world::with_world(|w| w.velocity(p, s, e, &agent, others));
    (v[0], v[1])
}

/// Apply velocity (vx, vy) (m/s) to human `i`: threshold the speed, turn to the velocity, move.
pub fn walk(p: &StepParams, s: &mut StateChunk, i: usize, vx: f32, vy: f32) {
    let mut speed = (vx * vx + vy * vy).sqrt();
    if speed < p.speed_threshold && s.h_forming[i] != crate::state::forming::CROWD {
        speed = 0.0;
    }
    let theta = math::atan2(vy, vx);
    let (sn, c) = math::sin_cos(theta);
    s.h_speed[i] = speed;
    s.h_theta[i] = theta;
    s.h_vx[i] = speed * c;
    s.h_vy[i] = speed * sn;
    s.h_x[i] += speed * p.dt * c;
    s.h_y[i] += speed * p.dt * sn;
}
