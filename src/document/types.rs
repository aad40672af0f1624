//! The state document as serde types: what [`export`](super::export) writes and
//! [`import`](super::import) reads, one type for both.
//!
//! Keys that socnav writes but does not read (they follow from the config or from other keys:
//! `counts`, `goals`, a group's `radius`, a laptop user's `centre`, ...) are
//! `skip_deserializing`: a document may hold anything there, as a golden episode's does. Keys a
//! golden episode has that socnav does not write (`group_noise`) are `skip_serializing`.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

use super::sngnn::Frame;
use super::values::{
    Angle, Code, F32, Flag, Id, Lazy, List, Min, Names, Noise, Object, Slot, U32, U64, Vector,
    object,
};
use crate::state::{blocker_kind, group_kind, policy, role, room_shape};

/// A whole document.
#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Document {
    /// [`FORMAT`](super::FORMAT); checked before the document is read (`check_envelope`).
    #[serde(skip_deserializing)]
    pub format: &'static str,
    pub room: Room,
    #[serde(default)]
    pub walls: List<Wall>,
    #[serde(default)]
    pub spawn_blockers: List<Blocker>,
    pub human_params: HumanParams,
    #[serde(skip_deserializing)]
    pub counts: Counts,
    pub state: Snapshot,
    /// What 0.1.1 does not have; a golden snapshot has none.
    pub socnav: Option<Extras>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Room {
    pub map_x: F32,
    pub map_y: F32,
    pub shape: Code<Shape>,
}

#[derive(Default, Serialize)]
pub(super) struct Counts {
    pub total_humans: u32,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Wall {
    pub id: U32,
    pub x: F32,
    pub y: F32,
    pub theta: Angle,
    pub length: F32,
    pub thickness: Option<F32>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Blocker {
    pub kind: Code<BlockerKind>,
    pub x: F32,
    pub y: F32,
    pub theta: Angle,
    pub length: F32,
    pub width: F32,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct HumanParams {
    #[serde(rename = "orca_neighborDist")]
    pub orca_neighbor_dist: F32,
    #[serde(rename = "orca_timeHorizon")]
    pub orca_time_horizon: F32,
    #[serde(rename = "orca_timeHorizonObst")]
    pub orca_time_horizon_obst: F32,
    #[serde(rename = "orca_maxSpeed")]
    pub orca_max_speed: F32,
    pub sfm_r0: F32,
    pub sfm_gamma: F32,
    pub sfm_n: F32,
    pub sfm_n_prime: F32,
    pub sfm_lambda: F32,
}

/// A golden state snapshot (golden README section 5), plus the SNGNN frames.
#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Snapshot {
    pub tick: U32,
    pub robot: Robot,
    pub shadow_robot: Shadow,
    #[serde(default)]
    pub humans: List<Human>,
    #[serde(default)]
    pub groups: List<Group>,
    #[serde(default)]
    pub hl_interactions: List<LaptopUser>,
    #[serde(default)]
    pub laptops: List<Laptop>,
    #[serde(default)]
    pub tables: List<Table>,
    #[serde(default)]
    pub plants: List<Plant>,
    pub crowd_forming: Option<CrowdForming>,
    pub hl_forming: Option<LaptopForming>,
    pub metrics: Metrics,
    pub reward_state: RewardState,
    /// The goal registry: "0" the robot's, a human's id its own; `[x, y, radius]`.
    #[serde(skip_deserializing)]
    pub goals: BTreeMap<String, [F32; 3]>,
    /// Replay: the noise the next step adds to these group members' velocities.
    #[serde(default, skip_serializing)]
    pub group_noise: List<Noise>,
    /// Newest first; read only by batches with the SNGNN reward, and only as many frames as
    /// they keep (module `sngnn`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sngnn_frames: Option<Lazy<List<Lazy<Frame>>>>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Robot {
    pub x: F32,
    pub y: F32,
    pub theta: Angle,
    pub radius: Option<F32>,
    pub goal: Vector<2>,
    pub goal_radius: Option<F32>,
    /// [vx, vy, ω] (m/s, m/s, rad/s).
    pub vel: Vector<3>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Shadow {
    pub x: F32,
    pub y: F32,
    pub theta: Angle,
    pub vel: Vector<3>,
    #[serde(default)]
    pub collided: Flag,
    #[serde(default)]
    pub reached: Flag,
    pub reach_tick: Option<U32>,
    pub path_length: F32,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Human {
    // Required keys in the order the golden format reads them (the first missing one is named).
    pub role: Code<Role>,
    pub id: U32,
    pub x: F32,
    pub y: F32,
    pub theta: Angle,
    pub speed: F32,
    pub radius: Option<F32>,
    pub goal: Option<Vector<2>>,
    /// Read for group members only (their group's member goal radius).
    pub goal_radius: Option<Lazy<F32>>,
    pub policy: Code<Policy>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub group: Option<U32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hl: Option<U32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forming_crowd: Option<Flag>,
    /// Read only when `forming_crowd` is not true.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forming_hl: Option<Lazy<Flag>>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Group {
    pub members: List<Id, true>,
    pub kind: Code<GroupKind>,
    #[serde(default)]
    pub dispersable: Flag,
    pub centre: Vector<2>,
    pub goal: Option<Vector<2>>,
    #[serde(skip_deserializing)]
    pub goal_radius: F32,
    #[serde(skip_deserializing)]
    pub radius: F32,
    #[serde(skip_deserializing)]
    pub noise: F32,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct LaptopUser {
    pub human: U32,
    pub laptop: U32,
    #[serde(default)]
    pub dispersable: Flag,
    #[serde(skip_deserializing)]
    pub centre: [F32; 2],
    #[serde(skip_deserializing)]
    pub distance: F32,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Laptop {
    pub id: U32,
    pub x: F32,
    pub y: F32,
    pub theta: Angle,
    pub length: Option<F32>,
    pub width: Option<F32>,
    pub hl: Option<U32>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Table {
    pub id: U32,
    pub x: F32,
    pub y: F32,
    pub theta: Angle,
    pub length: Option<F32>,
    pub width: Option<F32>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Plant {
    pub id: U32,
    pub x: F32,
    pub y: F32,
    pub radius: Option<F32>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct CrowdForming {
    #[serde(skip_deserializing)]
    pub humans: Vec<u32>,
    pub slots: List<Slot, true>,
    /// Human id → slot index; its entries are judged with the slots (`validate`).
    pub slot_of: Object,
    pub centre: Vector<2>,
    pub almost_formed_count: U32,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct LaptopForming {
    pub human: U32,
    pub laptop: U32,
    /// [x, y, theta].
    pub seat: Vector<3>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Metrics {
    pub prev_goal_distance: F32,
    pub failure_to_progress: U32,
    pub stalled_time: F32,
    pub path_length: F32,
    pub v_min: Min,
    pub v_max: F32,
    pub v_avg: F32,
    pub prev_vel: Vector<2>,
    pub a_min: Min,
    pub a_max: F32,
    pub a_avg: F32,
    pub prev_a: Vector<2>,
    pub jerk_min: Min,
    pub jerk_max: F32,
    pub jerk_avg: F32,
    pub compliant_count: U32,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct RewardState {
    pub prev_distance: Option<F32>,
    pub info: RewardInfo,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct RewardInfo {
    #[serde(rename = "DISCOMFORT_SNGNN")]
    pub discomfort_sngnn: F32,
    #[serde(rename = "DISCOMFORT_DSRNN")]
    pub discomfort_dsrnn: F32,
    pub distance_reward: F32,
    pub alive_reward: F32,
    pub sngnn_reward: F32,
}

/// What 0.1.1 does not have.
#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Extras {
    pub episode: U32,
    /// Documents written before episode seeds existed lack them.
    pub seed: Option<U64>,
    pub next_seed: Option<U64>,
    #[serde(default)]
    pub done: Flag,
    #[serde(default)]
    pub pending_reset: Flag,
    pub episode_sums: Option<EpisodeSums>,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct EpisodeSums {
    #[serde(rename = "return")]
    pub ret: F32,
    pub min_human_distance: Min,
    pub min_obstacle_distance: Min,
    pub sum_average_obstacle_distance: F32,
    pub sum_time_to_collision: F32,
    pub sum_discomfort_dsrnn: F32,
    pub sum_sngnn_reward: F32,
}

// Each with the first key the golden format reads of it.
object!(
    Document: "room",
    Room: "map_x",
    Wall: "id",
    Blocker: "kind",
    HumanParams: "orca_neighborDist",
    Snapshot: "tick",
    Robot: "x",
    Shadow: "x",
    Human: "role",
    Group: "members",
    LaptopUser: "human",
    Laptop: "id",
    Table: "id",
    Plant: "id",
    CrowdForming: "slots",
    LaptopForming: "human",
    Metrics: "prev_goal_distance",
    RewardState: "info",
    RewardInfo: "DISCOMFORT_SNGNN",
    Extras: "episode",
    EpisodeSums: "return",
);

/// Room shapes (`room_shape::*`).
pub(super) struct Shape;
impl Names for Shape {
    const CODES: &'static [(&'static str, u32)] = &[
        ("square", room_shape::SQUARE),
        ("rectangle", room_shape::RECTANGLE),
        ("L", room_shape::L),
        ("no-walls", room_shape::NO_WALLS),
    ];
    fn refuse(name: &str) -> String {
        format!("{name:?} is not a room shape")
    }
}

/// Human roles (`role::*`).
pub(super) struct Role;
impl Names for Role {
    const CODES: &'static [(&'static str, u32)] = &[
        ("static", role::STATIC),
        ("dynamic", role::DYNAMIC),
        ("moving_group", role::MOVING_GROUP),
        ("standing_group", role::STANDING_GROUP),
        ("hl", role::LAPTOP_USER),
    ];
    fn refuse(name: &str) -> String {
        format!("{name:?} is not a human role")
    }
}

/// Walking policies (`policy::*`).
pub(super) struct Policy;
impl Names for Policy {
    const CODES: &'static [(&'static str, u32)] = &[("orca", policy::ORCA), ("sfm", policy::SFM)];
    fn refuse(name: &str) -> String {
        format!("{name:?} is not \"orca\" or \"sfm\"")
    }
}

/// Group kinds (`group_kind::*`).
pub(super) struct GroupKind;
impl Names for GroupKind {
    const CODES: &'static [(&'static str, u32)] = &[
        ("moving", group_kind::MOVING),
        ("standing", group_kind::STANDING),
    ];
    fn refuse(name: &str) -> String {
        format!("{name:?} is not \"moving\" or \"standing\"")
    }
}

/// Spawn blocker kinds (`blocker_kind::*`): a laptop's or a door's.
pub(super) struct BlockerKind;
impl Names for BlockerKind {
    const CODES: &'static [(&'static str, u32)] = &[
        ("laptop", blocker_kind::L_BLOCK),
        ("wall", blocker_kind::DOOR),
    ];
    fn refuse(name: &str) -> String {
        format!("{name:?} is not \"laptop\" or \"wall\"")
    }
}
