//! ORCA (optimal reciprocal collision avoidance) exactly as RVO2 2.0.3 computes it.
//!
//! The spec is docs/spec.md orca-sfm 1; the reference data
//! (`rvo2_*` files) is reproduced bit for bit by `tests/suite/orca/reference.rs`.
//!
//! # Two layers
//! * **Core, non-allocating, one agent at a time** (what the simulator step calls):
//!   [`process_obstacles`] turns polygons into an [`ObstacleSet`] (columns, viewed as
//!   [`ObstacleVerts`]); [`agent_neighbors`] / [`obstacle_neighbors`] select neighbours by brute
//!   force; [`compute_new_velocity`] builds the ORCA lines and solves the linear programs for one
//!   agent into a reusable [`OrcaScratch`], which keeps the lines readable afterwards.
//! * **Standalone**: a [`Scene`] and [`compute_velocities`] (one RVO2 `doStep`'s new
//!   velocities), [`compute_velocities_batch`] (scenes in parallel with rayon), and a
//!   [`Simulator`] that steps like `RVOSimulator::doStep`.
//!
//! # Float rules (bit-exactness with RVO2 and with the WGSL mirror)
//! All arithmetic is `f32` in RVO2's operation order: `v / s` is `inv = 1/s` then two
//! multiplies, `normalize(v) = v / |v|`, scalar·scalar·vector is `(s·s)·v`, `std::min/max` are
//! written out as comparisons. Only `+ - * /`, `sqrt`, `abs` and comparisons are used; never
//! `mul_add`. Units: positions in metres, velocities in m/s, times in s.
//!
//! # Calling the core once per agent
//! ```
//! use socnav::orca::*;
//!
//! // Once (or whenever the walls change): polygons -> processed obstacle columns.
//! let walls = [vec![[-10.0_f32, 1.5], [10.0, 1.5]], vec![[10.0, -1.5], [-10.0, -1.5]]];
//! let (mut set, mut obstacle_scratch) = (ObstacleSet::new(), ObstacleScratch::new());
//! process_obstacles(&walls, &mut obstacle_scratch, &mut set)?;
//!
//! // Start-of-step state as columns.
//! let agent = |x: f32| OrcaAgent {
//!     pos: [x, 0.0], vel: [0.0, 0.0], pref_vel: [-x.signum(), 0.0], radius: 0.3,
//!     max_speed: 1.0, neighbor_dist: 10.0, max_neighbors: 10, time_horizon: 5.0,
//!     time_horizon_obst: 5.0,
//! };
//! let agents = [agent(-2.0), agent(2.0)];
//! let xs: Vec<f32> = agents.iter().map(|a| a.pos[0]).collect();
//! let ys: Vec<f32> = agents.iter().map(|a| a.pos[1]).collect();
//!
//! // Per step, per agent (buffers reused; no allocation once warm).
//! let (mut nb, mut gathered, mut scratch) = (Vec::new(), Vec::new(), OrcaScratch::new());
//! let mut new_vel = Vec::new();
//! for (i, a) in agents.iter().enumerate() {
//!     agent_neighbors(i, &xs, &ys, a.neighbor_dist, a.max_neighbors, &mut nb);
//!     gathered.clear();
//!     gathered.extend(nb.iter().map(|n| {
//!         let o = &agents[n.index as usize];
//!         OrcaNeighbor { pos: o.pos, vel: o.vel, radius: o.radius }
//!     }));
//!     new_vel.push(compute_new_velocity(a, &gathered, &set.as_view(), 0.25, &mut scratch));
//! }
//! // Then, for every agent: vel = new_vel; pos += vel * dt.
//!
//! // The same step through the standalone API.
//! let scene = Scene { time_step: 0.25, agents: agents.to_vec(), obstacles: walls.to_vec() };
//! assert_eq!(compute_velocities(&scene)?, new_vel);
//! # Ok::<(), OrcaError>(())
//! ```
//!
//! # Neighbour order and ties
//! The neighbour order sets the line order and so the float result. Brute force (index order)
//! equals RVO2 except when two candidate distances tie exactly: RVO2 then keeps its k-d tree's
//! visiting order. [`AgentKdTree`] and [`obstacle_neighbors_tree`] reproduce that order; the
//! standalone API uses them, so it matches RVO2 even in symmetric scenes. Measured on the
//! reference data: for agents, ties only decide anything with more than 10 agents (1 of 88 750
//! Circle250 restart agent-steps); for obstacles, the edges meeting at the nearest corner tie
//! often (34 of 2542 one-step agents get another edge order by brute force), yet the lines and
//! velocities of all 34 stay bit-identical. In general they need not: prefer the tree walk where
//! exact RVO2 order matters.

mod error;
mod kdtree;
mod lines;
mod lp;
mod neighbors;
mod obstacle_build;
mod obstacles;
mod scene;
mod vector;

pub use error::OrcaError;
pub use kdtree::AgentKdTree;
pub use lines::{Line, push_agent_lines, push_obstacle_lines};
pub use lp::{lp1, lp2, lp3};
pub use neighbors::{
    Neighbor, OBSTACLE_REJECT_FACTOR, agent_neighbors, insert_agent_neighbor,
    insert_obstacle_neighbor, obstacle_neighbors, obstacle_neighbors_tree, obstacle_range_sq,
};
pub use obstacle_build::{first_zero_length_edge, process_obstacles};
pub use obstacles::{NONE, ObstacleScratch, ObstacleSet, ObstacleTree, ObstacleVerts, RVO_EPSILON};
pub use scene::{AgentRecord, Scene, Simulator, compute_velocities, compute_velocities_batch};
pub use vector::{Vec2, det, dist_sq_point_segment, left_of};

/// One agent's state and parameters for an ORCA step (RVO2's `Agent`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrcaAgent {
    /// Position (m).
    pub pos: [f32; 2],
    /// Velocity used in the previous step (m/s).
    pub vel: [f32; 2],
    /// Preferred velocity for this step (m/s); not clamped by the library.
    pub pref_vel: [f32; 2],
    /// Disc radius (m).
    pub radius: f32,
    /// Radius of the admissible velocity disc (m/s).
    pub max_speed: f32,
    /// Agent neighbours must be closer than this, centre to centre (m, strict).
    pub neighbor_dist: f32,
    /// At most this many nearest agents are avoided; 0 disables agent avoidance.
    pub max_neighbors: u32,
    /// Time horizon for agents τ (s, > 0).
    pub time_horizon: f32,
    /// Time horizon for obstacles τo (s, > 0); also sets the obstacle search range.
    pub time_horizon_obst: f32,
}

impl OrcaAgent {
    /// Checks that every field is finite and in range (index `agent` goes into the error).
    ///
    /// # Errors
    /// [`OrcaError::InvalidParameter`] naming the first offending field.
    pub fn validate(&self, agent: usize) -> Result<(), OrcaError> {
        let bad = |name: &'static str, value: f32, reason: &'static str| {
            Err(OrcaError::InvalidParameter {
                agent: Some(agent),
                name,
                value,
                reason,
            })
        };
        let vectors = [
            ("pos", self.pos),
            ("vel", self.vel),
            ("pref_vel", self.pref_vel),
        ];
        for (name, v) in vectors {
            for c in v {
                if !c.is_finite() {
                    return bad(name, c, "must be finite");
                }
            }
        }
        let non_negative = [
            ("radius", self.radius),
            ("max_speed", self.max_speed),
            ("neighbor_dist", self.neighbor_dist),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, v, "must be finite and >= 0");
            }
        }
        let positive = [
            ("time_horizon", self.time_horizon),
            ("time_horizon_obst", self.time_horizon_obst),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, v, "must be finite and > 0");
            }
        }
        Ok(())
    }
}

/// The state of one agent neighbour that its ORCA line needs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OrcaNeighbor {
    /// Position at the start of the step (m).
    pub pos: [f32; 2],
    /// Velocity at the start of the step (m/s).
    pub vel: [f32; 2],
    /// Disc radius (m).
    pub radius: f32,
}

/// Reusable per-thread working memory of [`compute_new_velocity`].
///
/// After a call it holds that agent's ORCA lines (obstacle lines first), the obstacle
/// neighbours and whether LP3 ran. Its vectors keep their capacity, so once warm (capacity at
/// least the largest line count seen) a call does not allocate. An agent has at most
/// `obstacle neighbours + max_neighbors` lines; LP3's projection buffer needs as many entries.
#[derive(Clone, Debug, Default)]
pub struct OrcaScratch {
    lines: Vec<Line>,
    proj: Vec<Line>,
    obstacle_neighbors: Vec<Neighbor>,
    num_obstacle_lines: usize,
    lp2_fail: usize,
}

impl OrcaScratch {
    /// Empty scratch; grows on first use.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Scratch with room for `lines` ORCA lines and `obstacle_neighbors` obstacle edges, so the
    /// first calls do not allocate either.
    #[must_use]
    pub fn with_capacity(lines: usize, obstacle_neighbors: usize) -> Self {
        Self {
            lines: Vec::with_capacity(lines),
            proj: Vec::with_capacity(lines),
            obstacle_neighbors: Vec::with_capacity(obstacle_neighbors),
            num_obstacle_lines: 0,
            lp2_fail: 0,
        }
    }

    /// Make room for `lines` ORCA lines and `obstacle_neighbors` obstacle edges now, so that no
    /// later call allocates (a no-op when the capacity is already there).
    pub fn reserve(&mut self, lines: usize, obstacle_neighbors: usize) {
        self.lines.reserve(lines.saturating_sub(self.lines.len()));
        self.proj.reserve(lines.saturating_sub(self.proj.len()));
        self.obstacle_neighbors
            .reserve(obstacle_neighbors.saturating_sub(self.obstacle_neighbors.len()));
    }

    /// The last agent's ORCA lines: obstacle lines, then one per agent neighbour.
    #[must_use]
    pub fn lines(&self) -> &[Line] {
        &self.lines
    }

    /// How many of [`OrcaScratch::lines`] are obstacle lines (hard constraints in LP3).
    #[must_use]
    pub fn num_obstacle_lines(&self) -> usize {
        self.num_obstacle_lines
    }

    /// The last agent's obstacle neighbours (edge start vertices, nearest first).
    #[must_use]
    pub fn obstacle_neighbors(&self) -> &[Neighbor] {
        &self.obstacle_neighbors
    }

    /// True if the last agent's LP2 failed and LP3 computed its velocity.
    #[must_use]
    pub fn used_lp3(&self) -> bool {
        self.lp2_fail < self.lines.len()
    }
}

/// Computes one agent's new velocity (m/s), RVO2's `computeNeighbors` (obstacle part) plus
/// `computeNewVelocity`.
///
/// * `agent_neighbors`: the agent's neighbours, already selected and sorted (e.g. with
///   [`agent_neighbors`]), with their start-of-step state.
/// * `obstacles`: processed obstacle vertices; the edges are selected by brute force
///   ([`obstacle_neighbors`]).
/// * `time_step`: the simulation step (s), used when agents already overlap.
///
/// Reads only start-of-step data, so calling it for every agent and then applying the results
/// gives RVO2's Jacobi update. The lines stay readable in `scratch`.
///
/// Like RVO2, it does not guard against degenerate input: two agents at the same position with
/// the same velocity, or non-positive time horizons, give NaN.
pub fn compute_new_velocity(
    agent: &OrcaAgent,
    agent_neighbors: &[OrcaNeighbor],
    obstacles: &ObstacleVerts<'_>,
    time_step: f32,
    scratch: &mut OrcaScratch,
) -> [f32; 2] {
    let range_sq = obstacle_range_sq(agent.time_horizon_obst, agent.max_speed, agent.radius);
    obstacle_neighbors(
        agent.pos,
        range_sq,
        obstacles,
        &mut scratch.obstacle_neighbors,
    );
    solve(agent, agent_neighbors, obstacles, time_step, scratch)
}

/// [`compute_new_velocity`], but obstacle edges are selected by walking RVO2's tree
/// ([`obstacle_neighbors_tree`]), so exactly tied edge distances keep RVO2's order too.
pub fn compute_new_velocity_tree(
    agent: &OrcaAgent,
    agent_neighbors: &[OrcaNeighbor],
    obstacles: &ObstacleSet,
    time_step: f32,
    scratch: &mut OrcaScratch,
) -> [f32; 2] {
    let range_sq = obstacle_range_sq(agent.time_horizon_obst, agent.max_speed, agent.radius);
    let view = obstacles.as_view();
    obstacle_neighbors_tree(
        agent.pos,
        range_sq,
        &view,
        &obstacles.tree(),
        &mut scratch.obstacle_neighbors,
    );
    solve(agent, agent_neighbors, &view, time_step, scratch)
}

/// Lines from `scratch.obstacle_neighbors` and `agent_neighbors`, then LP2 and, if it fails, LP3.
fn solve(
    agent: &OrcaAgent,
    agent_neighbors: &[OrcaNeighbor],
    obstacles: &ObstacleVerts<'_>,
    time_step: f32,
    scratch: &mut OrcaScratch,
) -> [f32; 2] {
    let lines = &mut scratch.lines;
    lines.clear();
    push_obstacle_lines(agent, obstacles, &scratch.obstacle_neighbors, lines);
    scratch.num_obstacle_lines = lines.len();
    push_agent_lines(agent, agent_neighbors, time_step, lines);

    let pref = Vec2::from_array(agent.pref_vel);
    let (fail, v) = lp2(lines, agent.max_speed, pref, false);
    scratch.lp2_fail = fail;
    let v = if fail < lines.len() {
        lp3(
            lines,
            scratch.num_obstacle_lines,
            fail,
            agent.max_speed,
            v,
            &mut scratch.proj,
        )
    } else {
        v
    };
    v.to_array()
}
