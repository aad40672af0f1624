//! How SocNavGym 0.1.1 puts one agent into RVO2 (docs/spec.md 4.3, 4.4, 8.2): a fresh simulator per
//! agent per step whose other agents are the lone humans, optionally the robot, and the moving
//! groups as super-agents, over the environment's processed obstacles. Only the first agent's
//! new velocity is read, so this module builds that agent, picks its neighbours as RVO2 would
//! and runs the solver once.
//!
//! A walker with a field of view narrower than 0.1.1's "sees everything" tolerance meets only the
//! lone humans, moving groups and obstacles it sees (`perception.rs`); the robot, when it avoids
//! it, whether seen or not, as 0.1.1 adds it. Moving groups and the shadow robot see everything.
//!
//! In a fresh simulator every agent has zero velocity (the 0.1.1 choice, kept by default);
//! `model.orca_neighbour_velocity = "actual"` gives the agents their current velocities instead.

use std::cell::RefCell;

use crate::geometry::Shape;
use crate::orca::{
    Neighbor, OrcaAgent, OrcaNeighbor, OrcaScratch, compute_new_velocity, insert_agent_neighbor,
};
use crate::params::StepParams;
use crate::state::{StateChunk, group_kind};

use super::orca_obstacles;
use super::perception::{self, View};

/// Reusable per-thread buffers (they keep their capacity, so a warm step does not allocate).
#[derive(Debug, Default)]
pub struct OrcaWorld {
    candidates: Vec<OrcaNeighbor>,
    selected: Vec<Neighbor>,
    neighbors: Vec<OrcaNeighbor>,
    scratch: OrcaScratch,
}

thread_local! {
    static WORLD: RefCell<OrcaWorld> = RefCell::new(OrcaWorld::default());
}

/// Run `f` with this thread's ORCA buffers.
pub fn with_world<R>(f: impl FnOnce(&mut OrcaWorld) -> R) -> R {
    WORLD.with(|w| f(&mut w.borrow_mut()))
}

/// Which agents besides the first one the simulator holds.
#[derive(Debug, Clone, Copy)]
pub struct Others {
    /// Human slot of the first agent (excluded from the others), if it is a human.
    pub skip_human: Option<usize>,
    /// Group slot of the first agent (excluded), if it is a group.
    pub skip_group: Option<usize>,
    /// Whether the robot is one of the agents.
    pub robot: bool,
    /// The first agent's view: only the lone humans, moving groups and obstacles it sees take
    /// part. `None`: it sees everything (the environment's cached obstacles are used as they are).
    pub view: Option<View>,
}

/// Radius (m) of a moving group's ORCA super-agent: member circle plus a human diameter.
#[inline]
pub fn group_agent_radius(p: &StepParams) -> f32 {
    p.group_radius + 2.0 * p.human_radius
}

/// Preferred velocity of speed `speed` (m/s) from (x, y) towards (gx, gy); zero at the goal.
#[inline]
pub fn preferred(x: f32, y: f32, gx: f32, gy: f32, speed: f32) -> [f32; 2] {
    let (dx, dy) = (gx - x, gy - y);
    let l = (dx * dx + dy * dy).sqrt();
    if l > 0.0 {
        [speed * (dx / l), speed * (dy / l)]
    } else {
        [0.0, 0.0]
    }
}

/// An ORCA agent with the environment's per-episode parameters.
pub fn agent(
    s: &StateChunk,
    e: usize,
    pos: [f32; 2],
    vel: [f32; 2],
    pref: [f32; 2],
    radius: f32,
) -> OrcaAgent {
    OrcaAgent {
        pos,
        vel,
        pref_vel: pref,
        radius,
        max_speed: s.orca_max_speed[e],
        neighbor_dist: s.orca_neighbor_dist[e],
        max_neighbors: s.n_humans[e],
        time_horizon: s.orca_time_horizon[e],
        time_horizon_obst: s.orca_time_horizon_obst[e],
    }
}

impl OrcaWorld {
    /// The new velocity (m/s) of `first` in a simulator holding `others` of environment `e`.
    pub fn velocity(
        &mut self,
        p: &StepParams,
        s: &StateChunk,
        e: usize,
        first: &OrcaAgent,
        others: Others,
    ) -> [f32; 2] {
        self.reserve(&s.strides);
        self.gather(p, s, e, others);
        self.select(first);
        let (neighbors, scratch) = (&self.neighbors, &mut self.scratch);
        match &others.view {
            None => compute_new_velocity(
                first,
                neighbors,
                &orca_obstacles::obstacles(s, e),
                p.dt,
                scratch,
            ),
            Some(view) => orca_obstacles::with_visible(p, s, e, view, first, |seen| {
                compute_new_velocity(first, neighbors, seen, p.dt, scratch)
            }),
        }
    }

    /// Room for the largest simulator the capacities allow, reserved on a thread's first call so
    /// that no later call allocates: every human and group plus the robot as candidates, and one
    /// ORCA line per candidate and per obstacle edge.
    fn reserve(&mut self, caps: &crate::state::Caps) {
        let agents = caps.humans + caps.groups + 1;
        for v in [&mut self.candidates, &mut self.neighbors] {
            v.reserve(agents.saturating_sub(v.len()));
        }
        self.selected
            .reserve(agents.saturating_sub(self.selected.len()));
        self.scratch
            .reserve(caps.obstacle_vertices + agents, caps.obstacle_vertices);
    }

    /// The other agents in 0.1.1's order: lone humans, the robot, moving groups (those seen).
    fn gather(&mut self, p: &StepParams, s: &StateChunk, e: usize, others: Others) {
        let actual = p.orca_actual_velocity != 0;
        let view = others.view.as_ref();
        self.candidates.clear();
        let hb = e * s.strides.humans;
        for i in hb..hb + (s.n_static[e] + s.n_dynamic[e]) as usize {
            if others.skip_human == Some(i) || !perception::sees_human(view, p, s, e, i) {
                continue;
            }
            let vel = if actual {
                [s.h_vx[i], s.h_vy[i]]
            } else {
                [0.0, 0.0]
            };
            self.candidates.push(OrcaNeighbor {
                pos: [s.h_x[i], s.h_y[i]],
                vel,
                radius: p.human_radius,
            });
        }
        if others.robot {
            let vel = if actual {
                let (vx, vy) = super::robot_motion::robot_world_velocity(s, e);
                [vx, vy]
            } else {
                [0.0, 0.0]
            };
            self.candidates.push(OrcaNeighbor {
                pos: [s.robot_x[e], s.robot_y[e]],
                vel,
                radius: p.robot_radius,
            });
        }
        let gb = e * s.strides.groups;
        for g in gb..gb + s.n_groups[e] as usize {
            if s.g_kind[g] != group_kind::MOVING
                || others.skip_group == Some(g)
                || !perception::sees(view, &Shape::Disc(perception::group_disc(p, s, g)))
            {
                continue;
            }
            let vel = if actual {
                [s.g_vx[g], s.g_vy[g]]
            } else {
                [0.0, 0.0]
            };
            self.candidates.push(OrcaNeighbor {
                pos: [s.g_x[g], s.g_y[g]],
                vel,
                radius: group_agent_radius(p),
            });
        }
    }

    /// RVO2's neighbour selection for the first agent (nearest first, ties in agent order).
    fn select(&mut self, first: &OrcaAgent) {
        self.selected.clear();
        let mut range_sq = first.neighbor_dist * first.neighbor_dist;
        for (j, c) in self.candidates.iter().enumerate() {
            let dx = first.pos[0] - c.pos[0];
            let dy = first.pos[1] - c.pos[1];
            let candidate = Neighbor {
                dist_sq: dx * dx + dy * dy,
                index: j as u32,
            };
            insert_agent_neighbor(
                &mut self.selected,
                first.max_neighbors as usize,
                candidate,
                &mut range_sq,
            );
        }
        self.neighbors.clear();
        for n in &self.selected {
            self.neighbors.push(self.candidates[n.index as usize]);
        }
    }
}
