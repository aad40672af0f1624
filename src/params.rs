//! `StepParams`: every constant a stage reads, flattened from the [`Config`] into 4-byte scalars.
//! It is the only struct that crosses to the GPU (a read-only storage buffer), so it is
//! `#[repr(C)]`, `Pod`, built from `f32`/`u32`/`i32` fields and arrays of them only, and its size
//! is a multiple of 16 bytes. It is declared once, through `step_params!`, which also lists its
//! fields with their WGSL types ([`StepParams::WGSL_FIELDS`]): the shaders' struct is generated
//! from that list (`backend::wgsl::step_params_struct`), never written by hand.

use bytemuck::{Pod, Zeroable};

use crate::config::{
    Config, ContactShape, HumanPolicy, Kinematics, LaptopUserObstacle, ObsFrame,
    OrcaNeighbourVelocity, RewardKind, Shape,
};
use crate::geometry::contact_shape;

/// How finished environments are reset (docs/spec.md, step and autoreset).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AutoresetMode {
    /// The step after a finished one resets it and returns the first observation (gymnasium's default).
    #[default]
    NextStep,
    /// The finishing step resets at once; the final observation and info are kept aside.
    SameStep,
    /// Finished environments wait for the caller to reset them with a mask.
    Disabled,
}

impl AutoresetMode {
    /// The `u32` code carried in [`StepParams::autoreset`].
    pub fn code(self) -> u32 {
        match self {
            AutoresetMode::NextStep => 0,
            AutoresetMode::SameStep => 1,
            AutoresetMode::Disabled => 2,
        }
    }
}

/// Room shape codes in [`StepParams::shape`] (`random` draws among the first three).
pub mod shape_code {
    /// Square.
    pub const SQUARE: u32 = 0;
    /// Rectangle.
    pub const RECTANGLE: u32 = 1;
    /// L-shaped.
    pub const L: u32 = 2;
    /// No walls.
    pub const NO_WALLS: u32 = 3;
    /// Rectangle, square or L per episode.
    pub const RANDOM: u32 = 4;
}

/// A type a [`StepParams`] field may have, as the shaders see it: a 4-byte scalar, or an array
/// (nested or not) of one scalar type, which WGSL holds flat (`[[i32; 2]; 12]` is
/// `array<i32, 24>`). The field list of [`StepParams::WGSL_FIELDS`] comes from these, so a field
/// needs no annotation.
pub trait WgslValue {
    /// The WGSL scalar type of its elements: `f32`, `u32` or `i32`.
    const SCALAR: &'static str;
    /// Scalars it holds (1 for a scalar).
    const LEN: usize;
}

impl WgslValue for f32 {
    const SCALAR: &'static str = "f32";
    const LEN: usize = 1;
}

impl WgslValue for u32 {
    const SCALAR: &'static str = "u32";
    const LEN: usize = 1;
}

impl WgslValue for i32 {
    const SCALAR: &'static str = "i32";
    const LEN: usize = 1;
}

impl<T: WgslValue, const N: usize> WgslValue for [T; N] {
    const SCALAR: &'static str = T::SCALAR;
    const LEN: usize = N * T::LEN;
}

/// One field of [`StepParams`] as the shaders' struct has it (`backend::wgsl::step_params_struct`
/// writes the struct from the list).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WgslField {
    /// The Rust field's name (`_pad` for the padding; [`WgslField::wgsl_name`] drops the `_`).
    pub name: &'static str,
    /// The WGSL scalar type of its elements ([`WgslValue::SCALAR`]).
    pub scalar: &'static str,
    /// Scalars it holds ([`WgslValue::LEN`]): a scalar when 1, else a flat array.
    pub len: usize,
    /// Its byte offset in the Rust struct (`offset_of!`).
    pub offset: usize,
    /// Its size in bytes in the Rust struct.
    pub size: usize,
}

impl WgslField {
    /// The member's WGSL name: the Rust name without a leading `_` (the shaders read the padding
    /// as `pad[0]`, an opaque zero).
    pub fn wgsl_name(&self) -> &'static str {
        self.name.trim_start_matches('_')
    }

    /// The member's WGSL type: the scalar, or `array<scalar, len>`.
    pub fn wgsl_type(&self) -> String {
        if self.len == 1 {
            self.scalar.to_owned()
        } else {
            format!("array<{}, {}>", self.scalar, self.len)
        }
    }
}

/// Declares [`StepParams`] once: the `#[repr(C)]` struct itself and, from the same field list,
/// [`StepParams::WGSL_FIELDS`], from which the shaders' twin is generated. Every field's type is a
/// [`WgslValue`] of 4-byte scalars, which the macro checks, so that repr(C) inserts no padding
/// and every field is 4-byte aligned, as in a WGSL storage struct.
macro_rules! step_params {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $( $(#[$fmeta:meta])* pub $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        pub struct $name {
            $( $(#[$fmeta])* pub $field: $ty, )*
        }

        const _: () = {
            $( assert!(
                std::mem::size_of::<$ty>() == 4 * <$ty as WgslValue>::LEN
                    && std::mem::align_of::<$ty>() == 4
            ); )*
        };

        impl $name {
            /// Every field in declaration order, with its WGSL type and its Rust offset and
            /// size (`backend::wgsl::step_params_struct` writes the WGSL struct from it).
            pub const WGSL_FIELDS: &'static [WgslField] = &[$( WgslField {
                name: stringify!($field),
                scalar: <$ty as WgslValue>::SCALAR,
                len: <$ty as WgslValue>::LEN,
                offset: std::mem::offset_of!($name, $field),
                size: std::mem::size_of::<$ty>(),
            }, )*];
        }
    };
}

step_params! {
    /// Flattened constants of a step (units as in the config: m, s, rad).
    #[repr(C)]
    #[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
    pub struct StepParams {
        /// Time step (s).
        pub dt: f32,
        /// Episode length (steps); truncation when the tick exceeds it.
        pub episode_length: u32,
        /// Robot radius (m).
        pub robot_radius: f32,
        /// Robot goal radius (m).
        pub goal_radius: f32,
        /// Robot speed scale (m/s).
        pub robot_max_speed: f32,
        /// Robot rotation scale (rad/s).
        pub robot_max_rotation: f32,
        /// 1 for a holonomic robot, 0 for differential drive.
        pub holonomic: u32,
        /// Human radius (m).
        pub human_radius: f32,
        /// Lone human goal radius (m).
        pub human_goal_radius: f32,
        /// Human preferred/maximum speed (m/s).
        pub human_max_speed: f32,
        /// Speed threshold below which humans stop (m/s).
        pub speed_threshold: f32,
        /// Gaze cone width (rad).
        pub gaze_angle: f32,
        /// Human field of view (rad).
        pub fov_angle: f32,
        /// Probability per step that a human considers the robot.
        pub prob_avoid_robot: f32,
        /// Human policy: 0 ORCA, 1 SFM, 2 random per human.
        pub human_policy: u32,
        /// Group member circle radius (m).
        pub group_radius: f32,
        /// Moving-group goal radius (m).
        pub group_goal_radius: f32,
        /// Group velocity noise standard deviation (m/s).
        pub group_noise_std: f32,
        /// Seat distance beyond the laptop width (m).
        pub human_laptop_distance: f32,
        /// Laptop width, local y (m).
        pub laptop_width: f32,
        /// Laptop length, local x (m).
        pub laptop_length: f32,
        /// Plant radius (m).
        pub plant_radius: f32,
        /// Table width, local y (m).
        pub table_width: f32,
        /// Table length, local x (m).
        pub table_length: f32,
        /// Wall thickness (m).
        pub wall_thickness: f32,
        /// Observed wall segment length (m).
        pub wall_segment_size: f32,
        /// Sampling margin from the map border (m).
        pub margin: f32,
        /// Room shape code (`shape_code::*`).
        pub shape: u32,
        /// 1 to add corridor walls.
        pub corridors: u32,
        /// Room x size range (m, inclusive integers).
        pub size_x_min: i32,
        /// Upper end of the x size range.
        pub size_x_max: i32,
        /// Room y size range (m).
        pub size_y_min: i32,
        /// Upper end of the y size range.
        pub size_y_max: i32,
        /// Entity count ranges `[min, max]` in the order of [`crate::config::Counts::named`].
        pub counts: [[i32; 2]; 12],
        /// Crowd dispersal probability per step.
        pub p_crowd_dispersal: f32,
        /// Laptop-use dispersal probability per step.
        pub p_laptop_dispersal: f32,
        /// Crowd formation probability per step.
        pub p_crowd_formation: f32,
        /// Laptop-use formation probability per step.
        pub p_laptop_formation: f32,
        /// Reward kind: 0 DSRNN, 1 SNGNN.
        pub reward_kind: u32,
        /// Reward for reaching the goal.
        pub reward_reach: f32,
        /// Reward for leaving the map.
        pub reward_out_of_map: f32,
        /// Reward on timeout.
        pub reward_timeout: f32,
        /// Reward on collision.
        pub reward_collision: f32,
        /// Reward per non-terminal step.
        pub reward_alive: f32,
        /// Distance term scale (1/m).
        pub reward_distance_scale: f32,
        /// Discomfort clearance threshold (m).
        pub reward_discomfort_distance: f32,
        /// Discomfort scale.
        pub reward_discomfort_factor: f32,
        /// Weight (1/m) of the personal-space intrusion; 0 skips the term.
        pub reward_personal_space_weight: f32,
        /// Personal space (m) beyond the robot's surface.
        pub reward_personal_space_distance: f32,
        /// Weight (1/m) of the obstacle intrusion; 0 skips the term.
        pub reward_obstacle_weight: f32,
        /// Obstacle clearance (m) from the robot's surface.
        pub reward_obstacle_distance: f32,
        /// Weight of a stalled step; 0 skips the term.
        pub reward_stalled_weight: f32,
        /// Weight (s²/m) of the command's acceleration; 0 skips the term.
        pub reward_acceleration_weight: f32,
        /// 1 when the observation omits walls and pads every type (0.1.1 padded mode).
        pub obs_padded: u32,
        /// 1 when the robot record carries its commanded velocity.
        pub obs_robot_velocity: u32,
        /// 1 when the records are written in the world frame (`WorldFrameObservations`).
        pub obs_world_frame: u32,
        /// 1 when the field of view or the range hides anything (`PartialObservations`); 0 skips
        /// the visibility tests.
        pub obs_partial: u32,
        /// Robot field of view (rad), centred on its heading.
        pub obs_fov: f32,
        /// Sensor range (m); `f32::MAX` when unlimited (no infinity crosses to the GPU).
        pub obs_range: f32,
        /// 1 when any entry of `obs_noise` is on; 0 skips the noise pass.
        pub obs_noise_on: u32,
        /// Sensor noise (mean, standard deviation) per type: entity types at their
        /// [`crate::spec::entity`] index, the robot's goal at [`NOISE_ROBOT`].
        pub obs_noise: [[f32; 2]; 6],
        /// 1 when ORCA neighbours carry their velocities (0: at rest, as 0.1.1).
        pub orca_actual_velocity: u32,
        /// 1 when a moving group's ORCA velocity is divided by its member count (0.1.1).
        pub group_velocity_divided: u32,
        /// Half-side of a laptop user's ORCA obstacle square (m).
        pub laptop_user_half_side: f32,
        /// 1 when DSRNN discomfort counts groups and laptop uses as pseudo-humans (0.1.1).
        pub dsrnn_pseudo_humans: u32,
        /// Autoreset mode code ([`AutoresetMode::code`]).
        pub autoreset: u32,
        /// 1 in replay mode: the random social events are not drawn (the golden replay applies the
        /// recorded ones by re-synchronising).
        pub replay: u32,
        /// How the contact decisions model discs: a [`crate::geometry::contact_shape`] code
        /// (`[model] contact_shape`).
        pub contact_shape: u32,
        /// Padding to a multiple of 16 bytes; always 0 (the shaders use `pad[0]` as an opaque
        /// zero).
        pub _pad: [u32; 2],
    }
}

const _: () = assert!(std::mem::size_of::<StepParams>().is_multiple_of(16));

impl StepParams {
    /// Flatten `config` for a batch in autoreset mode `autoreset` (the seeds are per episode, in
    /// the state).
    pub fn new(config: &Config, autoreset: AutoresetMode) -> Self {
        let c = config;
        let counts = c.counts.named().map(|(_, r)| r);
        Self {
            dt: c.episode.time_step,
            episode_length: c.episode.length,
            robot_radius: c.robot.radius,
            goal_radius: c.robot.goal_radius,
            robot_max_speed: c.robot.max_speed,
            robot_max_rotation: c.robot.max_rotation,
            holonomic: u32::from(c.robot.kinematics == Kinematics::Holonomic),
            human_radius: 0.5 * c.human.diameter,
            human_goal_radius: c.human.goal_radius,
            human_max_speed: c.human.max_speed,
            speed_threshold: c.human.speed_threshold,
            gaze_angle: c.human.gaze_angle,
            fov_angle: c.human.fov_angle,
            prob_avoid_robot: c.human.prob_to_avoid_robot,
            human_policy: match c.human.policy {
                HumanPolicy::Orca => 0,
                HumanPolicy::Sfm => 1,
                HumanPolicy::Random => 2,
            },
            group_radius: c.group.radius,
            group_goal_radius: c.group.goal_radius,
            group_noise_std: c.group.velocity_noise_std,
            human_laptop_distance: c.laptop_use.human_distance,
            laptop_width: c.objects.laptop_width,
            laptop_length: c.objects.laptop_length,
            plant_radius: c.objects.plant_radius,
            table_width: c.objects.table_width,
            table_length: c.objects.table_length,
            wall_thickness: c.objects.wall_thickness,
            wall_segment_size: c.objects.wall_segment_size,
            margin: c.room.margin,
            shape: match c.room.shape {
                Shape::Square => shape_code::SQUARE,
                Shape::Rectangle => shape_code::RECTANGLE,
                Shape::L => shape_code::L,
                Shape::NoWalls => shape_code::NO_WALLS,
                Shape::Random => shape_code::RANDOM,
            },
            corridors: u32::from(c.room.corridors),
            size_x_min: c.room.size_x[0],
            size_x_max: c.room.size_x[1],
            size_y_min: c.room.size_y[0],
            size_y_max: c.room.size_y[1],
            counts,
            p_crowd_dispersal: c.events.crowd_dispersal_probability,
            p_laptop_dispersal: c.events.laptop_dispersal_probability,
            p_crowd_formation: c.events.crowd_formation_probability,
            p_laptop_formation: c.events.laptop_formation_probability,
            reward_kind: u32::from(c.reward.kind == RewardKind::Sngnn),
            reward_reach: c.reward.reach,
            reward_out_of_map: c.reward.out_of_map,
            reward_timeout: c.reward.timeout,
            reward_collision: c.reward.collision,
            reward_alive: c.reward.alive,
            reward_distance_scale: c.reward.distance_scale,
            reward_discomfort_distance: c.reward.discomfort_distance,
            reward_discomfort_factor: c.reward.discomfort_factor,
            reward_personal_space_weight: c.reward.personal_space_weight,
            reward_personal_space_distance: c.reward.personal_space_distance,
            reward_obstacle_weight: c.reward.obstacle_weight,
            reward_obstacle_distance: c.reward.obstacle_distance,
            reward_stalled_weight: c.reward.stalled_weight,
            reward_acceleration_weight: c.reward.acceleration_weight,
            obs_padded: u32::from(c.observation.padded),
            obs_robot_velocity: u32::from(c.observation.robot_velocity),
            obs_world_frame: u32::from(c.observation.frame == ObsFrame::World),
            obs_partial: u32::from(
                c.observation.fov < std::f32::consts::TAU || c.observation.range.is_some(),
            ),
            obs_fov: c.observation.fov,
            obs_range: c.observation.range.unwrap_or(f32::MAX),
            obs_noise_on: u32::from(c.observation.noise.named().iter().any(|(_, g)| g.is_on())),
            obs_noise: c.observation.noise.named().map(|(_, g)| [g.mean, g.std]),
            orca_actual_velocity: u32::from(
                c.model.orca_neighbour_velocity == OrcaNeighbourVelocity::Actual,
            ),
            group_velocity_divided: u32::from(c.model.group_velocity_divided),
            laptop_user_half_side: match c.model.laptop_user_obstacle {
                LaptopUserObstacle::Wide => 2.0 * c.human.diameter,
                LaptopUserObstacle::Radius => 0.5 * c.human.diameter,
            },
            dsrnn_pseudo_humans: u32::from(c.model.dsrnn_pseudo_humans),
            autoreset: autoreset.code(),
            replay: 0,
            contact_shape: match c.model.contact_shape {
                ContactShape::Exact => contact_shape::EXACT,
                ContactShape::Polygon64 => contact_shape::POLYGON64,
            },
            _pad: [0; 2],
        }
    }

    /// Count range `i` (order of [`crate::config::Counts::named`]).
    pub fn count_range(&self, i: usize) -> [i32; 2] {
        self.counts[i]
    }
}

/// Index of the robot's goal noise in [`StepParams::obs_noise`] (entity types use their
/// [`crate::spec::entity`] index).
pub const NOISE_ROBOT: usize = 5;

/// Indices into [`StepParams::counts`].
pub mod count {
    /// Lone static humans.
    pub const STATIC_HUMANS: usize = 0;
    /// Lone walking humans.
    pub const DYNAMIC_HUMANS: usize = 1;
    /// Tables.
    pub const TABLES: usize = 2;
    /// Plants.
    pub const PLANTS: usize = 3;
    /// Laptops.
    pub const LAPTOPS: usize = 4;
    /// Moving groups that may disperse.
    pub const MOVING_GROUPS: usize = 5;
    /// Moving groups that never disperse.
    pub const MOVING_GROUPS_ND: usize = 6;
    /// Standing groups that may disperse.
    pub const STANDING_GROUPS: usize = 7;
    /// Standing groups that never disperse.
    pub const STANDING_GROUPS_ND: usize = 8;
    /// Humans per group.
    pub const GROUP_SIZE: usize = 9;
    /// Laptop users who may leave.
    pub const LAPTOP_USERS: usize = 10;
    /// Laptop users who never leave.
    pub const LAPTOP_USERS_ND: usize = 11;
}
