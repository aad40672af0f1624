//! Stage `group_velocities` (docs/spec.md 4.4): every moving group is one ORCA super-agent (radius:
//! member circle plus a human diameter, neighbour distance twice that) heading for the group goal
//! at the human speed, in a simulator with the lone humans and the other moving groups (never the
//! robot). All groups are solved from the positions at the start of the step.

use crate::params::StepParams;
use crate::state::group_kind;

use super::Batch;
use super::orca_world::{self, Others};

/// Compute the ORCA velocity of each moving group of environment `e` into `g_vx`, `g_vy`.
pub fn group_velocities(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    let s = &mut b.s;
    if s.stepping[e] == 0 {
        return;
    }
    let gb = e * s.strides.groups;
    for g in gb..gb + s.n_groups[e] as usize {
        if s.g_kind[g] != group_kind::MOVING {
            continue;
        }
        let (x, y) = (s.g_x[g], s.g_y[g]);
        let pref = orca_world::preferred(x, y, s.g_goal_x[g], s.g_goal_y[g], p.human_max_speed);
        let radius = orca_world::group_agent_radius(p);
        let vel = if p.orca_actual_velocity != 0 {
            [s.g_vx[g], s.g_vy[g]]
        } else {
            [0.0, 0.0]
        };
        let mut agent = orca_world::agent(s, e, [x, y], vel, pref, radius);
        agent.neighbor_dist = 2.0 * radius;
        let others = Others {
            skip_human: None,
            skip_group: Some(g),
            robot: false,
            // Groups see everything (0.1.1 runs their simulator without a field of view).
            view: None,
        };
        let v = orca_world::with_world(|w| w.velocity(p, s, e, &agent, others));
        s.g_vx[g] = v[0];
        s.g_vy[g] = v[1];
    }
}
