//! The single source of truth for what a step returns: the observation layout, the info keys and
//! the per-episode statistics. The Python package builds its spaces from this module; no shape is
//! written twice.
//!
//! Observation of one environment (robot frame unless stated; docs/spec.md 5), flat `f32`:
//! `[robot record | humans × 14 | laptops × 14 | tables × 14 | plants × 14 | wall segments × 14]`.
//! Each entity type is padded with all-zero records to its capacity; per-type counts say how many
//! records are real. Without padding (`observation.padded = false`) the real records are exactly
//! 0.1.1's observation vectors; with padding the walls are omitted as in 0.1.1.
//!
//! The options of 0.1.1's observation wrappers (docs/spec.md 9.1) change the content, never the
//! shape of the entity blocks: `observation.frame = "world"` writes world-frame records and a
//! 16-float robot record ([`WORLD_ROBOT_RECORD`]); a limited field of view or range keeps the
//! visible records only, compacted to the front of their block; sensor noise is added in place.
//!
//! Beside the observation, the interactions of 0.1.1's `info["interactions"]` (docs/spec.md 5.2):
//! index pairs into the `humans` and `laptops` records, padded to [`ObsLayout::pairs`] per kind
//! ([`INTERACTION_KEYS`]) with per-kind counts.

use crate::config::{ObsFrame, Observation};
use crate::state::{BatchState, Caps};

/// Floats per entity record: one-hot type (6), x, y, sin, cos, radius, relative speed,
/// relative angular speed, gaze.
pub const RECORD: usize = 14;

/// Floats of a record's one-hot type, its first floats (the robot's record's too): 1.0 at the
/// type's place ([`one_hot`]) in a real record, all 0.0 in a padding record. An entity record's
/// one-hot floats are therefore a function of the per-type counts beside the row, which is why
/// the GPU backend keeps and reads back rows without them ([`ObsLayout::payload_dim`]).
pub const ONE_HOT: usize = 6;

/// Floats of the robot record without velocity: one-hot (6), goal x, goal y, radius.
pub const ROBOT_RECORD: usize = 9;

/// Floats of the world-frame robot record: one-hot (6), goal x, goal y, x, y (m, world frame),
/// sin θ, cos θ, the commanded v_x, v_y (m/s, robot frame), ω (rad/s), radius (m).
pub const WORLD_ROBOT_RECORD: usize = 16;

/// Interaction kinds of 0.1.1's `info["interactions"]`, in output order: pairs (i, j) of
/// `humans` record indices for every ordered pair of members of a group, and pairs (i, k) of a
/// laptop user's `humans` record index and its laptop's `laptops` record index.
pub const INTERACTION_KEYS: [&str; 2] = ["human-human", "human-laptop"];

/// Index of each interaction kind in [`INTERACTION_KEYS`] and in the per-kind pair counts.
pub mod interaction {
    /// Human-human pairs (group members).
    pub const HUMAN_HUMAN: usize = 0;
    /// Human-laptop pairs (laptop users).
    pub const HUMAN_LAPTOP: usize = 1;
}

/// Entity types in observation order, with their 0.1.1 dict keys.
pub const ENTITY_KEYS: [&str; 5] = ["humans", "laptops", "tables", "plants", "walls"];

/// Index of each entity type in [`ENTITY_KEYS`] and in the per-type count array.
pub mod entity {
    /// Humans.
    pub const HUMANS: usize = 0;
    /// Laptops.
    pub const LAPTOPS: usize = 1;
    /// Tables.
    pub const TABLES: usize = 2;
    /// Plants.
    pub const PLANTS: usize = 3;
    /// Wall segments.
    pub const WALLS: usize = 4;
}

/// One-hot position of each observed type (robot 0, human 1, table 2, laptop 3, plant 4, wall 5).
pub mod one_hot {
    /// Robot.
    pub const ROBOT: usize = 0;
    /// Human.
    pub const HUMAN: usize = 1;
    /// Table.
    pub const TABLE: usize = 2;
    /// Laptop.
    pub const LAPTOP: usize = 3;
    /// Plant.
    pub const PLANT: usize = 4;
    /// Wall.
    pub const WALL: usize = 5;
    /// The one-hot place of each entity type, in [`super::ENTITY_KEYS`] order.
    pub const OF_ENTITY: [usize; 5] = [HUMAN, LAPTOP, TABLE, PLANT, WALL];
}

/// Where each part of an environment's observation lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ObsLayout {
    /// Floats in the robot record: [`ROBOT_RECORD`] (9), 12 with the robot velocity, or
    /// [`WORLD_ROBOT_RECORD`] (16) in the world frame.
    pub robot: usize,
    /// Record capacity per entity type, in [`ENTITY_KEYS`] order.
    pub capacity: [usize; 5],
    /// Offset of each entity type's first record.
    pub offset: [usize; 5],
    /// Floats per environment.
    pub dim: usize,
    /// Pair capacity per interaction kind, in [`INTERACTION_KEYS`] order (each pair is two
    /// `u32` indices).
    pub pairs: [usize; 2],
}

impl ObsLayout {
    /// Layout for the given capacities and observation options.
    pub fn new(caps: &Caps, obs: &Observation) -> Self {
        let robot = match obs.frame {
            ObsFrame::World => WORLD_ROBOT_RECORD,
            ObsFrame::Robot if obs.robot_velocity => ROBOT_RECORD + 3,
            ObsFrame::Robot => ROBOT_RECORD,
        };
        let walls = if obs.padded { 0 } else { caps.wall_segments };
        let capacity = [caps.humans, caps.laptops, caps.tables, caps.plants, walls];
        let mut offset = [0; 5];
        let mut at = robot;
        for (o, n) in offset.iter_mut().zip(capacity) {
            *o = at;
            at += n * RECORD;
        }
        // A group of n members gives n(n - 1) ordered pairs, n - 1 per member. Every group (a
        // crowd formed during an episode too) has at most `group_size` members and a human is in
        // at most one group, so the members' pairs number at most humans × (group_size - 1).
        let human_human = caps.humans * caps.group_size.saturating_sub(1);
        Self {
            robot,
            capacity,
            offset,
            dim: at,
            pairs: [human_human, caps.laptop_users],
        }
    }

    /// Entity records of a row (one per slot of every type).
    pub fn entity_records(&self) -> usize {
        self.capacity.iter().sum()
    }

    /// Floats of a row without its entity records' [`ONE_HOT`] floats: the robot record whole,
    /// then every entity record's last `RECORD - ONE_HOT` floats, in row order.
    pub fn payload_dim(&self) -> usize {
        self.dim - ONE_HOT * self.entity_records()
    }
}

/// The info keys of docs/spec.md 8.2, in output order. Flags are 0.0 or 1.0; `None` in 0.1.1
/// (`TIME_TO_REACH_GOAL` before success, `AVERAGE_OBSTACLE_DISTANCE` without obstacles) is NaN;
/// infinities stay infinite.
pub const INFO_KEYS: [&str; 32] = [
    "OUT_OF_MAP",
    "SUCCESS",
    "COLLISION",
    "COLLISION_HUMAN",
    "COLLISION_OBJECT",
    "COLLISION_WALL",
    "TIMEOUT",
    "FAILURE_TO_PROGRESS",
    "STALLED_TIME",
    "TIME_TO_REACH_GOAL",
    "PATH_LENGTH",
    "V_MIN",
    "V_AVG",
    "V_MAX",
    "A_MIN",
    "A_AVG",
    "A_MAX",
    "JERK_MIN",
    "JERK_AVG",
    "JERK_MAX",
    "TIME_TO_COLLISION",
    "MINIMUM_DISTANCE_TO_HUMAN",
    "PERSONAL_SPACE_COMPLIANCE",
    "MINIMUM_OBSTACLE_DISTANCE",
    "AVERAGE_OBSTACLE_DISTANCE",
    "STL",
    "SPL",
    "DISCOMFORT_SNGNN",
    "DISCOMFORT_DSRNN",
    "distance_reward",
    "alive_reward",
    "sngnn_reward",
];

/// Index of each key in [`INFO_KEYS`].
pub mod info {
    #![expect(
        missing_docs,
        reason = "each constant is the index of the info key of the same name"
    )]
    pub const OUT_OF_MAP: usize = 0;
    pub const SUCCESS: usize = 1;
    pub const COLLISION: usize = 2;
    pub const COLLISION_HUMAN: usize = 3;
    pub const COLLISION_OBJECT: usize = 4;
    pub const COLLISION_WALL: usize = 5;
    pub const TIMEOUT: usize = 6;
    pub const FAILURE_TO_PROGRESS: usize = 7;
    pub const STALLED_TIME: usize = 8;
    pub const TIME_TO_REACH_GOAL: usize = 9;
    pub const PATH_LENGTH: usize = 10;
    pub const V_MIN: usize = 11;
    pub const V_AVG: usize = 12;
    pub const V_MAX: usize = 13;
    pub const A_MIN: usize = 14;
    pub const A_AVG: usize = 15;
    pub const A_MAX: usize = 16;
    pub const JERK_MIN: usize = 17;
    pub const JERK_AVG: usize = 18;
    pub const JERK_MAX: usize = 19;
    pub const TIME_TO_COLLISION: usize = 20;
    pub const MINIMUM_DISTANCE_TO_HUMAN: usize = 21;
    pub const PERSONAL_SPACE_COMPLIANCE: usize = 22;
    pub const MINIMUM_OBSTACLE_DISTANCE: usize = 23;
    pub const AVERAGE_OBSTACLE_DISTANCE: usize = 24;
    pub const STL: usize = 25;
    pub const SPL: usize = 26;
    pub const DISCOMFORT_SNGNN: usize = 27;
    pub const DISCOMFORT_DSRNN: usize = 28;
    pub const DISTANCE_REWARD: usize = 29;
    pub const ALIVE_REWARD: usize = 30;
    pub const SNGNN_REWARD: usize = 31;
}

/// Number of info keys.
pub const N_INFO: usize = INFO_KEYS.len();

/// The info keys 0.1.1 reports as booleans: the step's outcome flags.
pub const BOOL_INFO_KEYS: [&str; 7] = [
    INFO_KEYS[info::OUT_OF_MAP],
    INFO_KEYS[info::SUCCESS],
    INFO_KEYS[info::COLLISION],
    INFO_KEYS[info::COLLISION_HUMAN],
    INFO_KEYS[info::COLLISION_OBJECT],
    INFO_KEYS[info::COLLISION_WALL],
    INFO_KEYS[info::TIMEOUT],
];

/// The info keys 0.1.1 reports as integers (steps).
pub const INT_INFO_KEYS: [&str; 2] = [
    INFO_KEYS[info::FAILURE_TO_PROGRESS],
    INFO_KEYS[info::TIME_TO_COLLISION],
];

/// Per-episode statistics written when an episode ends, aggregated as the paper's table does
/// (docs/spec.md 8.3): outcome flags; `time_taken` (steps, the episode length on collision);
/// the final step's cumulative metrics; STL, SPL and TIME_TO_REACH_GOAL of the success step (0
/// and the episode length otherwise); minima over the steps; the mean obstacle distance and
/// time to collision over the steps (-1 counted as the episode length); discomfort sums.
pub const EPISODE_KEYS: [&str; 32] = [
    "return",
    "length",
    "success",
    "collision",
    "collision_human",
    "collision_object",
    "collision_wall",
    "timeout",
    "out_of_map",
    "time_taken",
    "FAILURE_TO_PROGRESS",
    "STALLED_TIME",
    "TIME_TO_REACH_GOAL",
    "PATH_LENGTH",
    "V_MIN",
    "V_AVG",
    "V_MAX",
    "A_MIN",
    "A_AVG",
    "A_MAX",
    "JERK_MIN",
    "JERK_AVG",
    "JERK_MAX",
    "PERSONAL_SPACE_COMPLIANCE",
    "STL",
    "SPL",
    "MINIMUM_DISTANCE_TO_HUMAN",
    "MINIMUM_OBSTACLE_DISTANCE",
    "AVERAGE_OBSTACLE_DISTANCE",
    "TIME_TO_COLLISION",
    "DISCOMFORT_DSRNN",
    "DISCOMFORT_SNGNN",
];

/// Number of per-episode statistics.
pub const N_EPISODE: usize = EPISODE_KEYS.len();

/// The per-episode outcome flags (1 or 0), whose means over episodes are the outcome rates:
/// [`EPISODE_KEYS`] from `success` to `out_of_map`.
pub const OUTCOME_KEYS: [&str; 7] = [
    EPISODE_KEYS[2],
    EPISODE_KEYS[3],
    EPISODE_KEYS[4],
    EPISODE_KEYS[5],
    EPISODE_KEYS[6],
    EPISODE_KEYS[7],
    EPISODE_KEYS[8],
];

/// The 7 discrete actions of 0.1.1's `DiscreteActions` wrapper, as continuous actions
/// (forward, lateral, rotation): turn left, turn right, forward + left, forward + right, forward,
/// backward, stop.
pub const DISCRETE_ACTIONS: [[f32; 3]; 7] = [
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
    [1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [1.0, 0.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 0.0, 0.0],
];

/// The social events counted per environment and step (outputs column `events`), in the order of
/// [`event`]: crowd dispersals, laptop-use dispersals, crowd formations started, completed, completed
/// approximately (the walkers stayed together for 25 steps) and given up (no free spot), laptop-use
/// formations started, blocked (seat taken) and completed.
pub const EVENT_KEYS: [&str; 9] = [
    "crowd_dispersal",
    "laptop_dispersal",
    "crowd_formation_start",
    "crowd_formation_complete",
    "crowd_formation_approximate",
    "crowd_formation_gave_up",
    "laptop_formation_start",
    "laptop_formation_blocked",
    "laptop_formation_complete",
];

/// Number of event kinds.
pub const N_EVENTS: usize = EVENT_KEYS.len();

/// Index of each event kind in [`EVENT_KEYS`].
pub mod event {
    #![expect(
        missing_docs,
        reason = "each constant is the index of the event key of the same name"
    )]
    pub const CROWD_DISPERSAL: usize = 0;
    pub const LAPTOP_DISPERSAL: usize = 1;
    pub const CROWD_FORMATION_START: usize = 2;
    pub const CROWD_FORMATION_COMPLETE: usize = 3;
    pub const CROWD_FORMATION_APPROXIMATE: usize = 4;
    pub const CROWD_FORMATION_GAVE_UP: usize = 5;
    pub const LAPTOP_FORMATION_START: usize = 6;
    pub const LAPTOP_FORMATION_BLOCKED: usize = 7;
    pub const LAPTOP_FORMATION_COMPLETE: usize = 8;
}

/// The info keys of environment `e`'s `row` (its [`INFO_KEYS`] values this step)
/// whose value is non-finite where the spec does not define it so (empty when none).
/// docs/spec.md 8.2 defines three: NaN where 0.1.1 has `None` (`TIME_TO_REACH_GOAL` before success,
/// `AVERAGE_OBSTACLE_DISTANCE` without obstacles) and +inf for "inf if none"
/// (`MINIMUM_DISTANCE_TO_HUMAN` without humans, `MINIMUM_OBSTACLE_DISTANCE` without walls, tables
/// and plants: a document may load a room without walls). `s` is the state the row describes.
pub fn info_outside_spec(s: &BatchState, e: usize, row: &[f32]) -> Vec<usize> {
    let no_obstacles = s.n_walls[e] + s.n_tables[e] + s.n_plants[e] == 0;
    let defined = |key: usize, v: f32| match key {
        _ if v.is_finite() => true,
        info::TIME_TO_REACH_GOAL => v.is_nan() && row[info::SUCCESS] == 0.0,
        info::AVERAGE_OBSTACLE_DISTANCE => v.is_nan() && no_obstacles,
        info::MINIMUM_DISTANCE_TO_HUMAN => v == f32::INFINITY && s.n_humans[e] == 0,
        info::MINIMUM_OBSTACLE_DISTANCE => v == f32::INFINITY && no_obstacles,
        _ => false,
    };
    (row.iter().enumerate())
        .filter(|&(key, &v)| !defined(key, v))
        .map(|(key, _)| key)
        .collect()
}
