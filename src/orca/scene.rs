//! The standalone ORCA API: a [`Scene`] solved in one call, batches of scenes in parallel, and
//! a [`Simulator`] that steps like `RVOSimulator::doStep`.
//!
//! Both use RVO2's k-d trees for neighbour order ([`AgentKdTree`], [`super::obstacle_neighbors_tree`]),
//! so they reproduce RVO2 bit for bit, ties included. [`compute_velocities`] is exactly the first
//! `doStep` of a fresh `RVOSimulator` holding the scene; a [`Simulator`] also keeps RVO2's
//! persistent agent order across steps.

use rayon::prelude::*;

use super::kdtree::AgentKdTree;
use super::lines::Line;
use super::neighbors::Neighbor;
use super::obstacle_build::process_obstacles;
use super::obstacles::{ObstacleScratch, ObstacleSet};
use super::{OrcaAgent, OrcaError, OrcaNeighbor, OrcaScratch, compute_new_velocity_tree};

/// One ORCA problem: agents, polygon obstacles and the time step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// Simulation time step (s, > 0). Used when two agents already overlap.
    pub time_step: f32,
    /// The agents, with start-of-step state and preferred velocities.
    pub agents: Vec<OrcaAgent>,
    /// Obstacle polygons: vertices `[x, y]` in metres, counter-clockwise; 2 vertices make a
    /// two-sided segment.
    pub obstacles: Vec<Vec<[f32; 2]>>,
}

impl Scene {
    /// Checks the time step and every agent.
    ///
    /// # Errors
    /// [`OrcaError::InvalidParameter`] for the first bad value found.
    pub fn validate(&self) -> Result<(), OrcaError> {
        validate_time_step(self.time_step)?;
        for (i, agent) in self.agents.iter().enumerate() {
            agent.validate(i)?;
        }
        Ok(())
    }
}

fn validate_time_step(time_step: f32) -> Result<(), OrcaError> {
    if time_step.is_finite() && time_step > 0.0 {
        Ok(())
    } else {
        Err(OrcaError::InvalidParameter {
            agent: None,
            name: "time_step",
            value: time_step,
            reason: "must be finite and > 0",
        })
    }
}

/// The new velocities (m/s) of one RVO2 `doStep` on `scene` (Jacobi: every agent sees the
/// start-of-step state of the others), in agent order.
///
/// # Errors
/// Invalid parameters, or obstacle polygons RVO2 cannot take (see [`OrcaError`]).
pub fn compute_velocities(scene: &Scene) -> Result<Vec<[f32; 2]>, OrcaError> {
    scene.validate()?;
    let mut sim = Simulator::new(scene.time_step)?;
    for agent in &scene.agents {
        sim.add_agent(*agent)?;
    }
    for polygon in &scene.obstacles {
        sim.add_obstacle(polygon.clone());
    }
    sim.process_obstacles()?;
    sim.compute_new_velocities();
    Ok(std::mem::take(&mut sim.new_vel))
}

/// [`compute_velocities`] for many scenes, in parallel with rayon. Results are in scene order
/// and do not depend on the thread count.
///
/// # Errors
/// The error of the first failing scene (in scene order).
pub fn compute_velocities_batch(scenes: &[Scene]) -> Result<Vec<Vec<[f32; 2]>>, OrcaError> {
    // Collect every result first: rayon's `Result` collection would report whichever error
    // a thread hit first, not the first in scene order.
    let results: Vec<Result<Vec<[f32; 2]>, OrcaError>> =
        scenes.par_iter().map(compute_velocities).collect();
    results.into_iter().collect()
}

/// What one agent's last ORCA solve saw and built (kept when recording is on).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AgentRecord {
    /// The ORCA lines: obstacle lines first, then one per agent neighbour.
    pub lines: Vec<Line>,
    /// How many of `lines` are obstacle lines.
    pub num_obstacle_lines: usize,
    /// Agent neighbours (agent indices), nearest first.
    pub agent_neighbors: Vec<u32>,
    /// Obstacle neighbours (edge start vertices), nearest first.
    pub obstacle_neighbors: Vec<u32>,
    /// True if LP3 produced the velocity.
    pub used_lp3: bool,
}

/// A small RVO2-style simulator: agents, obstacles and `do_step`.
///
/// Obstacles added with [`Simulator::add_obstacle`] are invisible until
/// [`Simulator::process_obstacles`] runs, as in RVO2.
#[derive(Clone, Debug)]
pub struct Simulator {
    time_step: f32,
    global_time: f32,
    agents: Vec<OrcaAgent>,
    polygons: Vec<Vec<[f32; 2]>>,
    obstacles: ObstacleSet,
    obstacle_scratch: ObstacleScratch,
    tree: AgentKdTree,
    scratch: OrcaScratch,
    pos_x: Vec<f32>,
    pos_y: Vec<f32>,
    neighbors: Vec<Neighbor>,
    gathered: Vec<OrcaNeighbor>,
    new_vel: Vec<[f32; 2]>,
    records: Option<Vec<AgentRecord>>,
}

impl Simulator {
    /// An empty simulator with time step `time_step` (s).
    ///
    /// # Errors
    /// [`OrcaError::InvalidParameter`] if `time_step` is not finite and positive.
    pub fn new(time_step: f32) -> Result<Self, OrcaError> {
        validate_time_step(time_step)?;
        Ok(Self {
            time_step,
            global_time: 0.0,
            agents: Vec::new(),
            polygons: Vec::new(),
            obstacles: ObstacleSet::new(),
            obstacle_scratch: ObstacleScratch::new(),
            tree: AgentKdTree::new(),
            scratch: OrcaScratch::new(),
            pos_x: Vec::new(),
            pos_y: Vec::new(),
            neighbors: Vec::new(),
            gathered: Vec::new(),
            new_vel: Vec::new(),
            records: None,
        })
    }

    /// Adds an agent and returns its index.
    ///
    /// # Errors
    /// [`OrcaError::InvalidParameter`] if a field is out of range.
    pub fn add_agent(&mut self, agent: OrcaAgent) -> Result<usize, OrcaError> {
        agent.validate(self.agents.len())?;
        self.agents.push(agent);
        Ok(self.agents.len() - 1)
    }

    /// Queues an obstacle polygon (m, counter-clockwise; 2 vertices = segment) and returns its
    /// index. It takes effect at the next [`Simulator::process_obstacles`].
    pub fn add_obstacle(&mut self, polygon: Vec<[f32; 2]>) -> usize {
        self.polygons.push(polygon);
        self.polygons.len() - 1
    }

    /// Builds the obstacle tree from every polygon added so far (RVO2's `processObstacles`).
    ///
    /// # Errors
    /// A polygon RVO2 cannot take (see [`process_obstacles`]); obstacles are then disabled until
    /// a successful call.
    pub fn process_obstacles(&mut self) -> Result<(), OrcaError> {
        process_obstacles(
            &self.polygons,
            &mut self.obstacle_scratch,
            &mut self.obstacles,
        )
    }

    /// The processed obstacles (vertex columns and tree).
    #[must_use]
    pub fn obstacles(&self) -> &ObstacleSet {
        &self.obstacles
    }

    /// The agents (current state and parameters).
    #[must_use]
    pub fn agents(&self) -> &[OrcaAgent] {
        &self.agents
    }

    /// Mutable access to agent `i` (set position, velocity, preferred velocity or parameters
    /// between steps; values are not re-validated).
    pub fn agent_mut(&mut self, i: usize) -> &mut OrcaAgent {
        &mut self.agents[i]
    }

    /// Sets agent `i`'s preferred velocity (m/s) for the next step.
    pub fn set_pref_velocity(&mut self, i: usize, pref_vel: [f32; 2]) {
        self.agents[i].pref_vel = pref_vel;
    }

    /// Simulated time (s): the sum of the steps taken, accumulated in `f32` as RVO2 does.
    #[must_use]
    pub fn global_time(&self) -> f32 {
        self.global_time
    }

    /// The time step (s).
    #[must_use]
    pub fn time_step(&self) -> f32 {
        self.time_step
    }

    /// Turns per-agent recording of lines and neighbours on or off (off by default).
    pub fn set_recording(&mut self, on: bool) {
        self.records = on.then(Vec::new);
    }

    /// What agent `i` saw in the last step, if recording was on.
    #[must_use]
    pub fn record(&self, i: usize) -> Option<&AgentRecord> {
        self.records.as_ref().and_then(|r| r.get(i))
    }

    /// One RVO2 `doStep`: all new velocities from the start-of-step state, then for every agent
    /// `vel = new_vel; pos += vel * time_step`.
    pub fn do_step(&mut self) {
        self.compute_new_velocities();
        for (agent, v) in self.agents.iter_mut().zip(&self.new_vel) {
            agent.vel = *v;
            agent.pos = [
                agent.pos[0] + v[0] * self.time_step,
                agent.pos[1] + v[1] * self.time_step,
            ];
        }
        self.global_time += self.time_step;
    }

    /// Fills `self.new_vel` (and the records) from the current state.
    fn compute_new_velocities(&mut self) {
        self.pos_x.clear();
        self.pos_y.clear();
        self.pos_x.extend(self.agents.iter().map(|a| a.pos[0]));
        self.pos_y.extend(self.agents.iter().map(|a| a.pos[1]));
        self.tree.build(&self.pos_x, &self.pos_y);
        self.new_vel.clear();
        if let Some(records) = &mut self.records {
            records.resize_with(self.agents.len(), AgentRecord::default);
        }
        for i in 0..self.agents.len() {
            let agent = self.agents[i];
            self.tree.agent_neighbors(
                i,
                &self.pos_x,
                &self.pos_y,
                agent.neighbor_dist,
                agent.max_neighbors,
                &mut self.neighbors,
            );
            self.gathered.clear();
            self.gathered.extend(self.neighbors.iter().map(|n| {
                let other = &self.agents[n.index as usize];
                OrcaNeighbor {
                    pos: other.pos,
                    vel: other.vel,
                    radius: other.radius,
                }
            }));
            let v = compute_new_velocity_tree(
                &agent,
                &self.gathered,
                &self.obstacles,
                self.time_step,
                &mut self.scratch,
            );
            self.new_vel.push(v);
            if let Some(records) = &mut self.records {
                let rec = &mut records[i];
                rec.lines.clear();
                rec.lines.extend_from_slice(self.scratch.lines());
                rec.num_obstacle_lines = self.scratch.num_obstacle_lines();
                rec.agent_neighbors.clear();
                rec.agent_neighbors
                    .extend(self.neighbors.iter().map(|n| n.index));
                rec.obstacle_neighbors.clear();
                rec.obstacle_neighbors
                    .extend(self.scratch.obstacle_neighbors().iter().map(|n| n.index));
                rec.used_lp3 = self.scratch.used_lp3();
            }
        }
    }
}
