//! Stage `goals` (docs/spec.md 4.1 step 8): a lone walker within reach of its goal (human radius +
//! goal radius) gets a new goal; a moving group whose members are all within reach of the group
//! goal (human radius + the members' own goal radius: the interaction goal radius for groups
//! spawned at reset, the human goal radius for crowds formed during the episode) gets a new group
//! goal. New goals are sampled in the margin box, free of every entity where it is now and of every
//! current goal; after a bounded number of tries the goal stays unchanged (0.1.1: a 30 s wall-clock
//! timeout).

use crate::geometry::{Disc, Shape, disc_disc};
use crate::params::StepParams;
use crate::rng::RngStream;
use crate::scenario::place::{MAX_TRIES, SamplingBox};
use crate::state::{StateChunk, group_kind};

use super::Batch;

/// RNG stream kind of goal re-sampling (`sub` = tick).
pub const STREAM_GOALS: u32 = 2;

/// Re-sample the goals reached in environment `e`.
pub fn goals(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    let s = &mut b.s;
    let mut rng = super::LazyStream::new(s, e, STREAM_GOALS);
    let hb = e * s.strides.humans;
    let first = hb + s.n_static[e] as usize;
    for i in first..first + s.n_dynamic[e] as usize {
        let reach = p.human_radius + p.human_goal_radius;
        if s.h_forming[i] == 0 && distance(s.h_x[i], s.h_y[i], s.h_goal_x[i], s.h_goal_y[i]) < reach
        {
            if let Some(g) = sample_goal(p, s, e, rng.get(), p.human_goal_radius) {
                s.h_goal_x[i] = g.x;
                s.h_goal_y[i] = g.y;
            }
        }
    }
    let gb = e * s.strides.groups;
    for g in gb..gb + s.n_groups[e] as usize {
        if s.g_kind[g] != group_kind::MOVING {
            continue;
        }
        // Each member within reach of the group goal by its own goal radius (0.1.1 asks every
        // member `has_reached_goal`), the same radius for all members of a group.
        let reach = p.human_radius + s.g_member_goal_radius[g];
        let members = hb + s.g_first[g] as usize..hb + (s.g_first[g] + s.g_count[g]) as usize;
        let arrived = members
            .clone()
            .all(|i| distance(s.h_x[i], s.h_y[i], s.g_goal_x[g], s.g_goal_y[g]) < reach);
        if arrived {
            if let Some(goal) = sample_goal(p, s, e, rng.get(), p.group_goal_radius) {
                s.g_goal_x[g] = goal.x;
                s.g_goal_y[g] = goal.y;
                for i in members {
                    s.h_goal_x[i] = goal.x;
                    s.h_goal_y[i] = goal.y;
                }
            }
        }
    }
}

#[inline]
fn distance(ax: f32, ay: f32, bx: f32, by: f32) -> f32 {
    let (dx, dy) = (ax - bx, ay - by);
    (dx * dx + dy * dy).sqrt()
}

/// A goal disc of radius `r` free of every entity and every current goal, or `None`.
pub fn sample_goal(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    rng: &mut RngStream,
    r: f32,
) -> Option<Disc> {
    let area = SamplingBox::new(p, s.map_x[e], s.map_y[e]);
    (0..MAX_TRIES).find_map(|_| {
        let (x, y) = area.point(rng);
        let d = Disc { x, y, r };
        let free =
            !super::world::blocks_goal(p, s, e, &Shape::Disc(d)) && !touches_goal(p, s, e, &d);
        free.then_some(d)
    })
}

/// Does the disc touch a current goal: the robot's, a lone human's or a moving group's?
pub fn touches_goal(p: &StepParams, s: &StateChunk, e: usize, d: &Disc) -> bool {
    if disc_disc(
        d,
        &Disc {
            x: s.goal_x[e],
            y: s.goal_y[e],
            r: p.goal_radius,
        },
    ) {
        return true;
    }
    let hb = e * s.strides.humans;
    let lone = hb..hb + (s.n_static[e] + s.n_dynamic[e]) as usize;
    if lone.into_iter().any(|i| {
        disc_disc(
            d,
            &Disc {
                x: s.h_goal_x[i],
                y: s.h_goal_y[i],
                r: p.human_goal_radius,
            },
        )
    }) {
        return true;
    }
    let gb = e * s.strides.groups;
    (gb..gb + s.n_groups[e] as usize).any(|g| {
        s.g_kind[g] == group_kind::MOVING
            && disc_disc(
                d,
                &Disc {
                    x: s.g_goal_x[g],
                    y: s.g_goal_y[g],
                    r: p.group_goal_radius,
                },
            )
    })
}
