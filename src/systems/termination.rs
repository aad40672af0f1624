//! Stage `termination` (docs/spec.md 8.1): decide the episode's outcome in 0.1.1's
//! priority order: out of map, goal reached, collision (with a human or an object), timeout.
//! Exactly one outcome flag is raised; `COLLISION_WALL` is reported whenever the robot touches a
//! wall. Every later stage reads the outcome from the info row. Touching is decided with discs
//! shaped as `[model] contact_shape` says ([`super::world::touches`]), for the shadow robot too.

use crate::geometry::Disc;
use crate::params::StepParams;
use crate::spec::info;

use super::Batch;

/// Outcome of the step for environment `e`.
pub fn termination(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    let s = &mut b.s;
    let (x, y) = (s.robot_x[e], s.robot_y[e]);
    let out_of_map = x.abs() > 0.5 * s.map_x[e] || y.abs() > 0.5 * s.map_y[e];
    let dx = s.goal_x[e] - x;
    let dy = s.goal_y[e] - y;
    let success = (dx * dx + dy * dy).sqrt() < p.robot_radius + p.goal_radius;
    let t = super::world::touches(
        p,
        s,
        e,
        &Disc {
            x,
            y,
            r: p.robot_radius,
        },
    );
    let timeout = s.tick[e] > p.episode_length;
    let mut flags = [false; 7];
    if out_of_map {
        flags[info::OUT_OF_MAP] = true;
    } else if success {
        flags[info::SUCCESS] = true;
    } else if t.human || t.object {
        flags[info::COLLISION] = true;
        flags[info::COLLISION_HUMAN] = t.human;
        flags[info::COLLISION_OBJECT] = t.object;
    } else if timeout {
        flags[info::TIMEOUT] = true;
    }
    flags[info::COLLISION_WALL] = t.wall;
    let row = &mut b.o.info[e * b.o.strides.info()..];
    for (k, f) in flags.iter().enumerate() {
        row[k] = if *f { 1.0 } else { 0.0 };
    }
    let terminated = out_of_map || success || t.human || t.object;
    let truncated = !terminated && timeout;
    b.o.terminated[e] = u32::from(terminated);
    b.o.truncated[e] = u32::from(truncated);
    s.done[e] = u32::from(terminated || truncated);
    super::shadow_robot::shadow_outcome(p, s, e);
}
