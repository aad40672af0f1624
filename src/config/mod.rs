//! Scenario configuration: every key of SocNavGym 0.1.1's YAML (docs/spec.md 2), grouped by
//! concern, in SI units (m, s, rad, m/s, rad/s).
//!
//! Defaults live in one place: the `Default` impls below, which reproduce the paper's
//! experiment 1 (`configs/exp1.toml`). A TOML file only needs the keys it changes. Loading
//! reports every problem at once: unknown keys, values that do not deserialise (an unknown
//! variant, a wrong type: each is reported and its line left out of a new parse) and the value
//! checks of [`validate`]. Unknown keys are collected with `serde_ignored` rather than refused by
//! serde's `deny_unknown_fields`, which would stop at the first one and hide every other problem.
//! `configs/README.md` documents every key with its unit, default and valid range.

pub mod bounds;
mod load;
mod socnavgym;
mod validate;

use serde::{Deserialize, Serialize};

pub use load::is_socnavgym_yaml;
pub use validate::validate;

/// The whole configuration of a batch of environments: what a SocNavGym 0.1.1 YAML file says.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct Config {
    /// Episode length and time step.
    pub episode: Episode,
    /// The robot's size, kinematics and speed limits.
    pub robot: Robot,
    /// Humans: size, goals, motion policy, perception.
    pub human: Human,
    /// Groups of humans ("crowds", human-human interactions).
    pub group: Group,
    /// Humans working at laptops (human-laptop interactions).
    pub laptop_use: LaptopUse,
    /// Sizes of the static objects.
    pub objects: Objects,
    /// Room shape and size.
    pub room: Room,
    /// How many of each entity kind a reset places (inclusive ranges).
    pub counts: Counts,
    /// Per-step probabilities of the social events (formation and dispersal).
    pub events: Events,
    /// The reward function and its constants.
    pub reward: Reward,
    /// What the observation contains.
    pub observation: Observation,
    /// Modelling choices of 0.1.1 kept under named options (see `docs/fidelity.md`).
    pub model: Model,
    /// Rendering settings (only used by `socnav render`).
    pub render: Render,
}

/// Episode length and time step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Episode {
    /// Maximum number of steps; the episode is truncated when the tick counter exceeds it
    /// (0.1.1 `episode_length`, so 200 gives 201 steps).
    pub length: u32,
    /// Integration step dt (s) for the robot, humans, ORCA, SFM and metrics (`time_step`).
    pub time_step: f32,
}

impl Default for Episode {
    fn default() -> Self {
        Self {
            length: 200,
            time_step: 1.0,
        }
    }
}

/// Robot kinematics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Kinematics {
    /// Differential drive: the lateral velocity is always 0 (0.1.1 `diff-drive`).
    #[serde(rename = "diff-drive")]
    DiffDrive,
    /// Holonomic: forward and lateral velocities are both commanded (0.1.1 `holonomic`).
    #[serde(rename = "holonomic")]
    Holonomic,
}

/// The robot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Robot {
    /// Disc radius (m) (`robot_radius`).
    pub radius: f32,
    /// Goal disc radius (m); success when the centre is within `radius + goal_radius` of the goal.
    pub goal_radius: f32,
    /// Kinematic model (`robot_type`).
    pub kinematics: Kinematics,
    /// Linear speed for an action of 1 (m/s) (`env.max_advance_robot`).
    pub max_speed: f32,
    /// Angular speed for an action of 1 (rad/s) (`env.max_rotation`).
    pub max_rotation: f32,
}

impl Default for Robot {
    fn default() -> Self {
        Self {
            radius: 0.25,
            goal_radius: 0.35,
            kinematics: Kinematics::DiffDrive,
            max_speed: 0.1,
            max_rotation: 0.387_596_9,
        }
    }
}

/// How a lone walking human chooses its velocity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HumanPolicy {
    /// Each spawned human draws ORCA or SFM with equal probability (0.1.1 `random`).
    Random,
    /// Optimal reciprocal collision avoidance (RVO2 semantics).
    Orca,
    /// Social force model (SocNavGym's one-shot variant).
    Sfm,
}

/// Humans.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Human {
    /// Disc diameter (m); the collision radius is half of it (`human_diameter`).
    pub diameter: f32,
    /// Radius of a lone human's goal disc (m) (`human_goal_radius`).
    pub goal_radius: f32,
    /// Motion policy of lone walking humans (`human_policy`).
    pub policy: HumanPolicy,
    /// Width of the gaze cone used for the observation's gaze flag (rad) (`gaze_angle`).
    pub gaze_angle: f32,
    /// Width of a human's field of view for its own ORCA/SFM perception (rad) (`fov_angle`).
    pub fov_angle: f32,
    /// Probability, drawn every step, that a human takes the robot into account (`prob_to_avoid_robot`).
    pub prob_to_avoid_robot: f32,
    /// Preferred and maximum speed (m/s) (`env.max_advance_human`).
    pub max_speed: f32,
    /// Speeds below this are set to 0 (m/s) (`env.speed_threshold`).
    pub speed_threshold: f32,
}

impl Default for Human {
    fn default() -> Self {
        Self {
            diameter: 0.72,
            goal_radius: 0.25,
            policy: HumanPolicy::Random,
            // 0.1.1's configs write these truncated decimals of π and 2π; the exact values matter
            // for gaze and field-of-view boundary decisions, so they are kept as written.
            #[expect(clippy::approx_constant, reason = "0.1.1's configs write π as 3.14159")]
            gaze_angle: 3.14159,
            #[expect(
                clippy::approx_constant,
                reason = "0.1.1's configs write 2π as 6.2831853"
            )]
            fov_angle: 6.283_185_3,
            prob_to_avoid_robot: 0.0,
            max_speed: 0.1,
            speed_threshold: 0.005,
        }
    }
}

/// Groups of humans (0.1.1 `human-human-interaction`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Group {
    /// Radius of the circle the members stand on (m) (`interaction_radius`).
    pub radius: f32,
    /// Radius of a moving group's goal disc (m) (`interaction_goal_radius`).
    pub goal_radius: f32,
    /// Standard deviation of the Gaussian noise added per axis to each member's velocity (m/s)
    /// (`noise_variance`, which 0.1.1 uses as a standard deviation despite its name).
    pub velocity_noise_std: f32,
}

impl Default for Group {
    fn default() -> Self {
        Self {
            radius: 0.72,
            goal_radius: 1.44,
            velocity_noise_std: 0.005,
        }
    }
}

/// Humans working at laptops (0.1.1 `human-laptop-interaction`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LaptopUse {
    /// Gap between the laptop and the seated human (m): the human sits
    /// `laptop.width + human_distance` from the laptop centre (`human_laptop_distance`).
    pub human_distance: f32,
}

impl Default for LaptopUse {
    fn default() -> Self {
        Self {
            human_distance: 0.3,
        }
    }
}

/// Sizes of static objects (m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Objects {
    /// Laptop extent along its local y axis (m) (`laptop_width`).
    pub laptop_width: f32,
    /// Laptop extent along its local x axis (m) (`laptop_length`).
    pub laptop_length: f32,
    /// Plant disc radius (m) (`plant_radius`).
    pub plant_radius: f32,
    /// Table extent along its local y axis (m) (`table_width`).
    pub table_width: f32,
    /// Table extent along its local x axis (m) (`table_length`).
    pub table_length: f32,
    /// Wall thickness (m), inside the map border (`wall_thickness`).
    pub wall_thickness: f32,
    /// Length of the wall segments the observation splits walls into (m) (`wall_segment_size`).
    pub wall_segment_size: f32,
}

impl Default for Objects {
    fn default() -> Self {
        Self {
            laptop_width: 0.4,
            laptop_length: 0.6,
            plant_radius: 0.4,
            table_width: 1.5,
            table_length: 3.0,
            wall_thickness: 0.2,
            wall_segment_size: 1.0,
        }
    }
}

/// Room shape (0.1.1 `set_shape`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Shape {
    /// A square room (y size = x size).
    #[serde(rename = "square")]
    Square,
    /// A rectangular room (x and y sizes drawn independently).
    #[serde(rename = "rectangle")]
    Rectangle,
    /// An L-shaped room: a square with one corner block removed.
    #[serde(rename = "L")]
    L,
    /// No walls: leaving the map ends the episode (`OUT_OF_MAP`).
    #[serde(rename = "no-walls")]
    NoWalls,
    /// Rectangle, square or L, drawn per episode.
    #[serde(rename = "random")]
    Random,
}

/// Room shape and size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Room {
    /// Room shape (`set_shape`).
    pub shape: Shape,
    /// Add two internal walls with one door each (`add_corridors`).
    pub corridors: bool,
    /// Inclusive range of the room's x size in whole metres (`min_map_x`, `max_map_x`).
    pub size_x: [i32; 2],
    /// Inclusive range of the room's y size in whole metres (`min_map_y`, `max_map_y`);
    /// ignored for square and L rooms, whose y size equals x.
    pub size_y: [i32; 2],
    /// Distance (m) from the map border of the box in which positions and goals are sampled (`margin`).
    pub margin: f32,
}

impl Default for Room {
    fn default() -> Self {
        Self {
            shape: Shape::Square,
            corridors: false,
            size_x: [10, 10],
            size_y: [10, 10],
            margin: 0.5,
        }
    }
}

/// Entity counts drawn at every reset, each an inclusive `[min, max]` range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Counts {
    /// Lone humans that never move (`min/max_static_humans`).
    pub static_humans: [i32; 2],
    /// Lone walking humans (`min/max_dynamic_humans`).
    pub dynamic_humans: [i32; 2],
    /// Tables (`min/max_tables`).
    pub tables: [i32; 2],
    /// Plants (`min/max_plants`).
    pub plants: [i32; 2],
    /// Laptops, on tables when any table exists (`min/max_laptops`).
    pub laptops: [i32; 2],
    /// Moving groups that may disperse (`min/max_h_h_dynamic_interactions`).
    pub moving_groups: [i32; 2],
    /// Moving groups that never disperse (`..._dynamic_interactions_non_dispersing`).
    pub moving_groups_non_dispersing: [i32; 2],
    /// Standing groups that may disperse (`min/max_h_h_static_interactions`).
    pub standing_groups: [i32; 2],
    /// Standing groups that never disperse (`..._static_interactions_non_dispersing`).
    pub standing_groups_non_dispersing: [i32; 2],
    /// Humans per group, drawn per group (`min/max_human_in_h_h_interactions`).
    pub group_size: [i32; 2],
    /// Humans working at a laptop who may leave (`min/max_h_l_interactions`).
    pub laptop_users: [i32; 2],
    /// Humans working at a laptop who never leave (`..._h_l_interactions_non_dispersing`).
    pub laptop_users_non_dispersing: [i32; 2],
}

impl Default for Counts {
    fn default() -> Self {
        Self {
            static_humans: [0, 0],
            dynamic_humans: [1, 1],
            tables: [0, 0],
            plants: [1, 1],
            laptops: [0, 0],
            moving_groups: [0, 0],
            moving_groups_non_dispersing: [0, 0],
            standing_groups: [0, 0],
            standing_groups_non_dispersing: [0, 0],
            group_size: [0, 0],
            laptop_users: [0, 0],
            laptop_users_non_dispersing: [0, 0],
        }
    }
}

impl Counts {
    /// Every range with its key name, for validation and capacity computations.
    pub fn named(&self) -> [(&'static str, [i32; 2]); 12] {
        [
            ("static_humans", self.static_humans),
            ("dynamic_humans", self.dynamic_humans),
            ("tables", self.tables),
            ("plants", self.plants),
            ("laptops", self.laptops),
            ("moving_groups", self.moving_groups),
            (
                "moving_groups_non_dispersing",
                self.moving_groups_non_dispersing,
            ),
            ("standing_groups", self.standing_groups),
            (
                "standing_groups_non_dispersing",
                self.standing_groups_non_dispersing,
            ),
            ("group_size", self.group_size),
            ("laptop_users", self.laptop_users),
            (
                "laptop_users_non_dispersing",
                self.laptop_users_non_dispersing,
            ),
        ]
    }

    /// The largest number of groups a reset can place (i64, negative maxima as 0: no overflow
    /// on absurd inputs, which validation reports).
    pub fn max_groups(&self) -> i64 {
        at_most(self.moving_groups)
            + at_most(self.moving_groups_non_dispersing)
            + at_most(self.standing_groups)
            + at_most(self.standing_groups_non_dispersing)
    }

    /// The largest number of laptop users a reset can place (as [`Counts::max_groups`]).
    pub fn max_laptop_users(&self) -> i64 {
        at_most(self.laptop_users) + at_most(self.laptop_users_non_dispersing)
    }

    /// The largest number of humans of every role a reset can place (i64: no overflow on
    /// absurd inputs, which validation reports).
    pub fn max_humans(&self) -> i64 {
        at_most(self.static_humans)
            + at_most(self.dynamic_humans)
            + self.max_laptop_users()
            + self.max_groups() * at_most(self.group_size)
    }

    /// The largest number of laptops, free and in use.
    pub fn max_laptops(&self) -> i64 {
        at_most(self.laptops) + self.max_laptop_users()
    }
}

/// A count range's maximum as i64, a negative one (which validation reports) as 0.
pub(super) fn at_most(range: [i32; 2]) -> i64 {
    i64::from(range[1].max(0))
}

/// Per-step probabilities of the social events, evaluated after the observation (docs/spec.md 4.5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct Events {
    /// Probability per step of dispersing one dispersable group (`crowd_dispersal_probability`).
    pub crowd_dispersal_probability: f32,
    /// Probability per step of ending one dispersable laptop use (`human_laptop_dispersal_probability`).
    pub laptop_dispersal_probability: f32,
    /// Probability per step of starting a crowd formation (`crowd_formation_probability`).
    pub crowd_formation_probability: f32,
    /// Probability per step of sending a walker to a free laptop (`human_laptop_formation_probability`).
    pub laptop_formation_probability: f32,
}

/// Which reward function scores a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RewardKind {
    /// The DSRNN-style reward (docs/spec.md 6.2).
    Dsrnn,
    /// The SNGNN-v2 data-driven reward (docs/spec.md 6.3).
    Sngnn,
}

/// The reward and its constants (docs/spec.md 6.2; the defaults are 0.1.1's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Reward {
    /// Reward function (`reward_file`).
    pub kind: RewardKind,
    /// Path of the SNGNN-v2 weight file (`SOCNAV_V2.tch`); `SOCNAV_SNGNN_WEIGHTS` overrides it.
    pub sngnn_weights: Option<String>,
    /// Reward for reaching the goal.
    pub reach: f32,
    /// Reward for leaving the map.
    pub out_of_map: f32,
    /// Reward when the episode times out.
    pub timeout: f32,
    /// Reward for a collision.
    pub collision: f32,
    /// Reward added to every non-terminal step.
    pub alive: f32,
    /// Scale of the potential-based distance term (1/m).
    pub distance_scale: f32,
    /// Predicted clearance (m) below which the discomfort term applies.
    pub discomfort_distance: f32,
    /// Scale of the discomfort term (1/(m s)).
    pub discomfort_factor: f32,
    /// Weight (1/m) of the personal-space term: how far (m) the nearest human's centre is inside
    /// `personal_space_distance` of the robot's surface. Not in 0.1.1; 0 leaves it out.
    pub personal_space_weight: f32,
    /// Personal space (m) beyond the robot's surface; 0.45 is the threshold of
    /// PERSONAL_SPACE_COMPLIANCE.
    pub personal_space_distance: f32,
    /// Weight (1/m) of the obstacle term: how far (m) the nearest plant, table or wall is inside
    /// `obstacle_distance` of the robot's surface. Not in 0.1.1; 0 leaves it out.
    pub obstacle_weight: f32,
    /// Clearance (m) from the robot's surface under which the obstacle term applies.
    pub obstacle_distance: f32,
    /// Weight of the stalled term: 1 on a step whose linear command is 0. Not in 0.1.1.
    pub stalled_weight: f32,
    /// Weight (s²/m) of the acceleration term: the magnitude (m/s²) of the change of the linear
    /// command over the step, as A_AVG measures it. Not in 0.1.1.
    pub acceleration_weight: f32,
}

impl Default for Reward {
    fn default() -> Self {
        Self {
            kind: RewardKind::Dsrnn,
            sngnn_weights: None,
            reach: 1.0,
            out_of_map: -1.0,
            timeout: -1.0,
            collision: -1.0,
            alive: -1e-5,
            distance_scale: 5.0,
            discomfort_distance: 0.6,
            discomfort_factor: 0.5,
            personal_space_weight: 0.0,
            personal_space_distance: 0.45,
            obstacle_weight: 0.0,
            obstacle_distance: 0.3,
            stalled_weight: 0.0,
            acceleration_weight: 0.0,
        }
    }
}

/// What the observation contains (docs/spec.md 5) and the options of 0.1.1's observation
/// wrappers (docs/spec.md 9.1), applied inside the step. The defaults are the bare 0.1.1
/// environment: robot frame, everything visible, no noise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Observation {
    /// Pad every entity type to its capacity and omit the walls (`get_padded_observations`).
    /// Off, the wall segments are observed; the batch layout is fixed either way.
    pub padded: bool,
    /// Append the robot's commanded velocity (v_x, v_y, omega) to the robot record (not in 0.1.1).
    /// Robot frame only: the world-frame robot record carries the command already.
    pub robot_velocity: bool,
    /// Frame of the records: the robot's (0.1.1) or the world's (`WorldFrameObservations`).
    pub frame: ObsFrame,
    /// Width of the robot's field of view (rad), centred on its heading
    /// (`PartialObservations.fov_angle`); 2π sees everything.
    pub fov: f32,
    /// Sensor range (m) from the robot centre (`PartialObservations.range`); `None` (the key
    /// omitted) is unlimited.
    pub range: Option<f32>,
    /// Gaussian sensor noise per observed type (`NoisyObservations`).
    pub noise: ObsNoise,
}

impl Default for Observation {
    fn default() -> Self {
        Self {
            padded: false,
            robot_velocity: false,
            frame: ObsFrame::Robot,
            // f32 2π: every bearing atan2(y, x) in [-π, π] lies within ±fov/2.
            fov: std::f32::consts::TAU,
            range: None,
            noise: ObsNoise::default(),
        }
    }
}

/// The frame the observation records are written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ObsFrame {
    /// Robot frame, x forward, y left (0.1.1's environment).
    Robot,
    /// World frame (0.1.1's `WorldFrameObservations` wrapper): a 16-float robot record with the
    /// robot's pose and command; entity records with world positions, headings and velocities.
    World,
}

/// Gaussian noise N(mean, std) added to observed values; `{ mean = 0, std = 0 }` is off.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct Gaussian {
    /// Mean (the unit of the field it is added to: m, m/s, rad/s or none).
    pub mean: f32,
    /// Standard deviation (same unit as the mean).
    pub std: f32,
}

impl Gaussian {
    /// Whether adding this noise changes anything.
    pub fn is_on(&self) -> bool {
        self.mean != 0.0 || self.std != 0.0
    }
}

/// Sensor noise per observed type (0.1.1's `NoisyObservations(mean, std_dev, apply_noise_to)`,
/// with one distribution per type instead of one shared distribution and a list of types).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct ObsNoise {
    /// Added to the robot record's goal x and y.
    pub robot: Gaussian,
    /// Added to fields 6-13 of every human record.
    pub humans: Gaussian,
    /// Added to fields 6-13 of every laptop record.
    pub laptops: Gaussian,
    /// Added to fields 6-13 of every table record.
    pub tables: Gaussian,
    /// Added to fields 6-13 of every plant record.
    pub plants: Gaussian,
    /// Added to fields 6-13 of every observed wall segment record.
    pub walls: Gaussian,
}

impl ObsNoise {
    /// Every distribution with its key name, entity types in observation order
    /// ([`crate::spec::ENTITY_KEYS`]), then the robot.
    pub fn named(&self) -> [(&'static str, Gaussian); 6] {
        [
            ("humans", self.humans),
            ("laptops", self.laptops),
            ("tables", self.tables),
            ("plants", self.plants),
            ("walls", self.walls),
            ("robot", self.robot),
        ]
    }
}

/// Which velocity the neighbours of an ORCA agent have.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OrcaNeighbourVelocity {
    /// 0.1.1: a fresh RVO2 simulator per human per step, so every agent is seen at rest.
    Zero,
    /// Neighbours carry their current velocities, as a persistent RVO2 simulator would.
    Actual,
}

/// How large the ORCA obstacle square of a laptop user is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LaptopUserObstacle {
    /// 0.1.1: a square of half-side 2 x human diameter (1.44 m in the paper configs).
    Wide,
    /// The intended square of half-side one human radius.
    Radius,
}

/// Which shapes the step's contact decisions use (the human push-out, the robot's and the shadow
/// robot's collisions); spawning and goal sampling always use exact discs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ContactShape {
    /// Exact discs and rectangles.
    Exact,
    /// Discs as 0.1.1's shapely 64-gons (`Point.buffer(r)`, vertices at k·π/32), rectangles
    /// exact: contacts decided as 0.1.1 decides them.
    Polygon64,
}

/// Modelling choices of 0.1.1 that socnav keeps by default under a named option
/// (docs/spec.md, fidelity; every row is in `docs/fidelity.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Model {
    /// Velocity of ORCA neighbours.
    pub orca_neighbour_velocity: OrcaNeighbourVelocity,
    /// Divide a moving group's ORCA velocity by its member count, as 0.1.1 does.
    pub group_velocity_divided: bool,
    /// ORCA obstacle size of laptop users.
    pub laptop_user_obstacle: LaptopUserObstacle,
    /// DSRNN discomfort also counts every group and laptop use as a pseudo-human at its centre.
    pub dsrnn_pseudo_humans: bool,
    /// Shapes of the step's contact decisions (an approximation of 0.1.1, not a modelling
    /// choice: exact by default).
    pub contact_shape: ContactShape,
}

impl Default for Model {
    fn default() -> Self {
        Self {
            orca_neighbour_velocity: OrcaNeighbourVelocity::Zero,
            group_velocity_divided: true,
            laptop_user_obstacle: LaptopUserObstacle::Wide,
            dsrnn_pseudo_humans: true,
            contact_shape: ContactShape::Exact,
        }
    }
}

/// Rendering settings (0.1.1 `rendering`), used only by `socnav render`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Render {
    /// Size of the longer image side in pixels (`resolution_view`).
    pub resolution: u32,
    /// Delay between animation frames in milliseconds (`milliseconds`).
    pub frame_ms: u32,
}

impl Default for Render {
    fn default() -> Self {
        Self {
            resolution: 1000,
            frame_ms: 30,
        }
    }
}
