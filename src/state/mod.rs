//! The batched structure-of-arrays state: one `Vec` per field, fixed capacities per entity kind
//! ([`Caps`]), per-environment counts. Element `slot` of environment `env` of a column of kind
//! `k` sits at `env * caps.k() + slot`.
//!
//! Invariants:
//! - Human slots are kept in the order of the `humans` observation: lone static humans
//!   (`n_static`), lone walking humans (`n_dynamic`), then the members of each group in group order
//!   (moving groups before standing groups), then laptop users. Social events that change roles
//!   permute slots to keep this order, so the observation is a plain walk over `0..n_humans`.
//! - Laptop slots: free laptops first, then those in use, in laptop-user order.
//! - Group `g`'s members are the `g_count[g]` consecutive human slots from `g_first[g]`.
//! - Entity ids (`*_id`) persist for the episode: robot 0, then spawn order (docs/spec.md 3.1).
//! - Unused slots hold zeros; `NONE` marks absent references.
//! - The SNGNN frame history (`sngnn` to `sngnn_entity` kinds) has zero capacity unless the
//!   config's reward is SNGNN-v2; its invariants are in [`crate::sngnn::history`].

pub mod caps;
pub mod columns;
pub mod invariants;

pub use crate::room::{blocker_kind, room_shape};
pub use caps::Caps;
use columns::soa;

/// An absent index (group of a lone human, laptop user of a free laptop, ...).
pub const NONE: u32 = u32::MAX;

/// Role of a human (column `h_role`).
pub mod role {
    /// A lone human that never moves.
    pub const STATIC: u32 = 0;
    /// A lone walking human with its own goal.
    pub const DYNAMIC: u32 = 1;
    /// A member of a moving group.
    pub const MOVING_GROUP: u32 = 2;
    /// A member of a standing group.
    pub const STANDING_GROUP: u32 = 3;
    /// A human seated at a laptop.
    pub const LAPTOP_USER: u32 = 4;
}

/// Motion policy of a human (column `h_policy`).
pub mod policy {
    /// ORCA (RVO2 semantics).
    pub const ORCA: u32 = 0;
    /// Social force model.
    pub const SFM: u32 = 1;
}

/// Kind of a group (column `g_kind`).
pub mod group_kind {
    /// Walks as one ORCA super-agent towards a group goal.
    pub const MOVING: u32 = 0;
    /// Stands still, members facing the centre.
    pub const STANDING: u32 = 1;
    /// Dissolved by a social event, removed at the next regrouping.
    pub const DISSOLVED: u32 = 2;
}

/// What a human is walking to (column `h_forming`).
pub mod forming {
    /// Nothing: an ordinary walker.
    pub const NONE: u32 = 0;
    /// Its slot in a forming crowd (speeds below the threshold are kept).
    pub const CROWD: u32 = 1;
    /// The seat at a laptop.
    pub const LAPTOP: u32 = 2;
}

soa! {
    /// The state of a batch of environments (see the module docs for the layout and invariants).
    pub struct BatchState / StateChunk over Caps {
        // ---- episode bookkeeping ----
        /// Episodes started since the environment was last seeded (a count; keys nothing).
        env.episode: u32,
        /// Low word of the episode seed: every draw of the episode is keyed by it
        /// (`crate::rng`, docs/spec.md, determinism).
        env.seed_lo: u32,
        /// High word of the episode seed.
        env.seed_hi: u32,
        /// Low word of the seed the environment's next episode will have (the next reset's).
        env.next_seed_lo: u32,
        /// High word of the next episode's seed.
        env.next_seed_hi: u32,
        /// Steps taken in the current episode (0 after reset).
        env.tick: u32,
        /// 1 once the episode has terminated or been truncated.
        env.done: u32,
        /// 1 when the next step must reset this environment first (NEXT_STEP autoreset).
        env.pending_reset: u32,
        /// 1 when this step's dynamics run for the environment (0 when it was reset instead).
        env.stepping: u32,
        /// 1 when the ORCA obstacle set must be rebuilt (obstacles appeared or vanished).
        env.obstacles_dirty: u32,
        /// The next list position (`*_seq`) to hand out: every append gets a larger one.
        env.seq_next: u32,
        // ---- room ----
        /// Room size along x (m).
        env.map_x: f32,
        /// Room size along y (m).
        env.map_y: f32,
        /// Room shape (`room_shape::*`).
        env.room_shape: u32,
        // ---- counts ----
        /// Humans of all roles.
        env.n_humans: u32,
        /// Lone static humans (slots `0..n_static`).
        env.n_static: u32,
        /// Lone walking humans (slots `n_static..n_static + n_dynamic`).
        env.n_dynamic: u32,
        /// Groups.
        env.n_groups: u32,
        /// Laptop users.
        env.n_laptop_users: u32,
        /// Laptops (free ones first).
        env.n_laptops: u32,
        /// Tables.
        env.n_tables: u32,
        /// Plants.
        env.n_plants: u32,
        /// Walls.
        env.n_walls: u32,
        /// Spawn blockers.
        env.n_blockers: u32,
        /// ORCA obstacle vertices.
        env.n_obstacle_vertices: u32,
        // ---- robot (world frame) ----
        /// Robot x (m).
        env.robot_x: f32,
        /// Robot y (m).
        env.robot_y: f32,
        /// Robot heading (rad), wrapped to (-π, π].
        env.robot_theta: f32,
        /// Last commanded forward velocity (m/s, robot frame).
        env.robot_vx: f32,
        /// Last commanded lateral velocity (m/s, robot frame).
        env.robot_vy: f32,
        /// Last commanded angular velocity (rad/s).
        env.robot_w: f32,
        /// World-frame velocity x (m/s) of the last command at the current heading (derived).
        env.robot_wvx: f32,
        /// World-frame velocity y (m/s) (derived).
        env.robot_wvy: f32,
        /// Robot goal x (m).
        env.goal_x: f32,
        /// Robot goal y (m).
        env.goal_y: f32,
        // ---- ORCA shadow robot, the reference for STL and SPL ----
        /// Shadow robot x (m).
        env.shadow_x: f32,
        /// Shadow robot y (m).
        env.shadow_y: f32,
        /// Shadow robot heading (rad).
        env.shadow_theta: f32,
        /// Shadow robot's last forward command (m/s).
        env.shadow_vx: f32,
        /// Shadow robot's last lateral command (m/s).
        env.shadow_vy: f32,
        /// Shadow robot's last angular command (rad/s).
        env.shadow_w: f32,
        /// 1 once the shadow robot collided.
        env.shadow_collided: u32,
        /// 1 once the shadow robot reached the goal.
        env.shadow_reached: u32,
        /// Tick at which the shadow robot reached the goal.
        env.shadow_reach_tick: u32,
        /// Distance the shadow robot was commanded to travel (m).
        env.shadow_path_length: f32,
        // ---- per-episode human parameters (docs/spec.md 4.3), shared by all humans ----
        /// RVO2 neighbour distance (m); may be negative, RVO2 only uses its square.
        env.orca_neighbor_dist: f32,
        /// RVO2 time horizon for agents (s).
        env.orca_time_horizon: f32,
        /// RVO2 time horizon for obstacles (s).
        env.orca_time_horizon_obst: f32,
        /// RVO2 maximum speed (m/s).
        env.orca_max_speed: f32,
        /// SFM obstacle-force range r0 (m).
        env.sfm_r0: f32,
        /// SFM γ.
        env.sfm_gamma: f32,
        /// SFM n.
        env.sfm_n: f32,
        /// SFM n'.
        env.sfm_n_prime: f32,
        /// SFM λ.
        env.sfm_lambda: f32,
        // ---- metric accumulators (docs/spec.md 8.2) ----
        /// Goal distance after the previous step (m).
        env.m_prev_goal_dist: f32,
        /// Steps that increased the goal distance.
        env.m_failure_to_progress: u32,
        /// Time with a zero linear command (s).
        env.m_stalled_time: f32,
        /// Commanded path length (m).
        env.m_path_length: f32,
        /// Running minimum linear speed (m/s).
        env.m_v_min: f32,
        /// Running maximum linear speed (m/s).
        env.m_v_max: f32,
        /// Running mean linear speed (m/s).
        env.m_v_avg: f32,
        /// Previous forward command (m/s).
        env.m_prev_vx: f32,
        /// Previous lateral command (m/s).
        env.m_prev_vy: f32,
        /// Running minimum acceleration magnitude (m/s²).
        env.m_a_min: f32,
        /// Running maximum acceleration magnitude (m/s²).
        env.m_a_max: f32,
        /// Running mean acceleration magnitude (m/s²).
        env.m_a_avg: f32,
        /// Previous acceleration, forward component (m/s²).
        env.m_prev_ax: f32,
        /// Previous acceleration, lateral component (m/s²).
        env.m_prev_ay: f32,
        /// Running minimum jerk magnitude (m/s³).
        env.m_j_min: f32,
        /// Running maximum jerk magnitude (m/s³).
        env.m_j_max: f32,
        /// Running mean jerk magnitude (m/s³).
        env.m_j_avg: f32,
        /// Steps that complied with personal space.
        env.m_compliant: u32,
        // ---- per-episode aggregates for the paper's table (docs/spec.md 8.3) ----
        /// Sum of rewards this episode.
        env.ep_return: f32,
        /// Minimum over steps of the robot-human centre distance (m).
        env.ep_min_human_dist: f32,
        /// Minimum over steps of the obstacle distance (m).
        env.ep_min_obstacle_dist: f32,
        /// Sum over steps of the average obstacle distance (m).
        env.ep_sum_avg_obstacle_dist: f32,
        /// Sum over steps of the time to collision (-1 counted as the episode length).
        env.ep_sum_ttc: f32,
        /// Sum of DISCOMFORT_DSRNN.
        env.ep_sum_discomfort_dsrnn: f32,
        /// Sum of sngnn_reward.
        env.ep_sum_sngnn: f32,
        // ---- reward memory (docs/spec.md 6.1: its info values persist) ----
        /// Goal distance at the previous non-terminal step (m).
        env.r_prev_dist: f32,
        /// 1 once `r_prev_dist` holds a value.
        env.r_has_prev: u32,
        /// DISCOMFORT_SNGNN of the last non-terminal step.
        env.r_discomfort_sngnn: f32,
        /// DISCOMFORT_DSRNN of the last non-terminal step.
        env.r_discomfort_dsrnn: f32,
        /// distance_reward of the last non-terminal step.
        env.r_distance: f32,
        /// alive_reward of the last non-terminal step.
        env.r_alive: f32,
        /// sngnn_reward of the last non-terminal step.
        env.r_sngnn: f32,
        // ---- crowd and laptop-use formation in progress (docs/spec.md 4.5) ----
        /// 1 while humans walk to a forming crowd.
        env.cf_active: u32,
        /// Members of the forming crowd.
        env.cf_count: u32,
        /// Centre of the forming crowd (m).
        env.cf_x: f32,
        /// Centre of the forming crowd (m).
        env.cf_y: f32,
        /// Consecutive steps the forming humans stayed close together.
        env.cf_close_steps: u32,
        /// 1 while a walker heads to a laptop seat.
        env.lf_active: u32,
        /// Human slot walking to the seat.
        env.lf_human: u32,
        /// Laptop slot of the seat.
        env.lf_laptop: u32,
        /// Seat pose (m, m, rad).
        env.lf_seat_x: f32,
        /// Seat pose (m).
        env.lf_seat_y: f32,
        /// Seat pose (rad).
        env.lf_seat_theta: f32,

        // ---- humans ----
        /// Entity id.
        human.h_id: u32,
        /// Position x (m).
        human.h_x: f32,
        /// Position y (m).
        human.h_y: f32,
        /// Heading (rad), not wrapped (standing-group members can be below -π, as in 0.1.1).
        human.h_theta: f32,
        /// Speed along the heading (m/s).
        human.h_speed: f32,
        /// World-frame velocity x (m/s): speed · cos(heading) (derived, set with speed and heading).
        human.h_vx: f32,
        /// World-frame velocity y (m/s): speed · sin(heading) (derived).
        human.h_vy: f32,
        /// Goal x (m); static humans' goal is their own position.
        human.h_goal_x: f32,
        /// Goal y (m).
        human.h_goal_y: f32,
        /// Motion policy once walking alone (`policy::*`).
        human.h_policy: u32,
        /// Role (`role::*`).
        human.h_role: u32,
        /// Group index or `NONE`.
        human.h_group: u32,
        /// Laptop-user index or `NONE`.
        human.h_laptop_user: u32,
        /// `forming::NONE`, or what the human is walking to (`forming::CROWD`, `forming::LAPTOP`).
        human.h_forming: u32,
        /// Position in its list (lone static, lone walking, its group's members, laptop users'
        /// humans): entries appended later get larger numbers; slots are sorted by it.
        human.h_seq: u32,
        /// Wrapped heading relative to the robot at the end of the previous step (rad), for the
        /// observed relative angular speed.
        human.h_prev_rel_theta: f32,
        /// Replay only: the group velocity noise (m/s) this member gets at the next step, as the
        /// golden episodes recorded it (`group_noise` in a state document); drawn otherwise.
        human.h_noise_x: f32,
        /// Replay only: the noise's y component (m/s).
        human.h_noise_y: f32,

        // ---- groups ----
        /// `group_kind::*`.
        group.g_kind: u32,
        /// 1 if the group may disperse.
        group.g_dispersable: u32,
        /// First member slot.
        group.g_first: u32,
        /// Number of members.
        group.g_count: u32,
        /// Stored centre x (m): the member centroid, except for approximate crowds (docs/spec.md
        /// 14).
        group.g_x: f32,
        /// Stored centre y (m).
        group.g_y: f32,
        /// Goal x (m) of a moving group.
        group.g_goal_x: f32,
        /// Goal y (m) of a moving group.
        group.g_goal_y: f32,
        /// Goal radius (m) of each member's own arrival test: 0.1.1 re-draws a moving group's goal
        /// when every member is within human radius + *its own* goal radius of it, which is the
        /// interaction goal radius for groups spawned at reset and the human goal radius for
        /// crowds formed during the episode (their members are the walkers that formed them).
        group.g_member_goal_radius: f32,
        /// This step's ORCA velocity x of a moving group (m/s, before the division by members).
        group.g_vx: f32,
        /// This step's ORCA velocity y (m/s).
        group.g_vy: f32,
        /// Position in its list (moving or standing groups).
        group.g_seq: u32,

        // ---- forming crowd slots ----
        /// Slot x (m).
        crowd_slot.cf_slot_x: f32,
        /// Slot y (m).
        crowd_slot.cf_slot_y: f32,
        /// Slot heading (rad).
        crowd_slot.cf_slot_theta: f32,
        /// Human slot walking to this crowd slot.
        crowd_slot.cf_human: u32,

        // ---- laptop users ----
        /// Human slot.
        laptop_user.lu_human: u32,
        /// Laptop slot.
        laptop_user.lu_laptop: u32,
        /// 1 if the user may leave.
        laptop_user.lu_dispersable: u32,
        /// Position in the list of laptop users.
        laptop_user.lu_seq: u32,

        // ---- laptops ----
        /// Entity id.
        laptop.l_id: u32,
        /// Centre x (m).
        laptop.l_x: f32,
        /// Centre y (m).
        laptop.l_y: f32,
        /// Heading (rad).
        laptop.l_theta: f32,
        /// cos of the heading (laptops never move; cached for the many rectangle tests).
        laptop.l_cos: f32,
        /// sin of the heading.
        laptop.l_sin: f32,
        /// Laptop-user index or `NONE` when free.
        laptop.l_user: u32,
        /// Position in the list of free laptops.
        laptop.l_seq: u32,

        // ---- tables ----
        /// Entity id.
        table.t_id: u32,
        /// Centre x (m).
        table.t_x: f32,
        /// Centre y (m).
        table.t_y: f32,
        /// Heading (rad).
        table.t_theta: f32,
        /// cos of the heading (tables never move; cached for the many rectangle tests).
        table.t_cos: f32,
        /// sin of the heading.
        table.t_sin: f32,

        // ---- plants ----
        /// Entity id.
        plant.p_id: u32,
        /// Centre x (m).
        plant.p_x: f32,
        /// Centre y (m).
        plant.p_y: f32,

        // ---- walls ----
        /// Entity id.
        wall.w_id: u32,
        /// Centre x (m).
        wall.w_x: f32,
        /// Centre y (m).
        wall.w_y: f32,
        /// Heading of the wall's long axis (rad).
        wall.w_theta: f32,
        /// cos of the heading (walls never move; cached for the many rectangle tests).
        wall.w_cos: f32,
        /// sin of the heading.
        wall.w_sin: f32,
        /// Length (m).
        wall.w_length: f32,

        // ---- spawn blockers ----
        /// `blocker_kind::*`.
        blocker.b_kind: u32,
        /// Centre x (m).
        blocker.b_x: f32,
        /// Centre y (m).
        blocker.b_y: f32,
        /// Heading (rad).
        blocker.b_theta: f32,
        /// Extent along the local x axis (m).
        blocker.b_length: f32,
        /// Extent along the local y axis (m).
        blocker.b_width: f32,

        // ---- ORCA obstacles after RVO2's processing ----
        /// Vertex x (m).
        obstacle_vertex.ov_x: f32,
        /// Vertex y (m).
        obstacle_vertex.ov_y: f32,
        /// Unit direction to the next vertex, x.
        obstacle_vertex.ov_dir_x: f32,
        /// Unit direction to the next vertex, y.
        obstacle_vertex.ov_dir_y: f32,
        /// Next vertex index.
        obstacle_vertex.ov_next: u32,
        /// Previous vertex index.
        obstacle_vertex.ov_prev: u32,
        /// 1 if the vertex is convex.
        obstacle_vertex.ov_convex: u32,

        // ---- SNGNN-v2 frame history (`sngnn::history`; zero-sized without the SNGNN reward) ----
        /// Frames held (at most `Caps::frames`).
        sngnn.sn_frame_count: u32,
        /// Ring slot of the newest frame.
        sngnn.sn_newest: u32,
        /// Tick of the step the frame was taken at (its timestamp is tick · dt).
        frame.sf_tick: u32,
        /// Robot x (m, world frame) when the frame was taken: places the walls in it.
        frame.sf_robot_x: f32,
        /// Robot y (m, world frame).
        frame.sf_robot_y: f32,
        /// Robot heading (rad, world frame).
        frame.sf_robot_theta: f32,
        /// Goal x (m, SNGNN axes: right of the robot).
        frame.sf_goal_x: f32,
        /// Goal y (m, SNGNN axes: ahead of the robot).
        frame.sf_goal_y: f32,
        /// Command: advance (SNGNN units, at most 3.5).
        frame.sf_advance: f32,
        /// Command: lateral advance (SNGNN units; 0 for a differential-drive robot).
        frame.sf_lateral: f32,
        /// Command: rotation (SNGNN units, within ±4).
        frame.sf_rotation: f32,
        /// People in the frame.
        frame.sf_n_people: u32,
        /// Objects in the frame.
        frame.sf_n_objects: u32,
        /// Interaction entries in the frame.
        frame.sf_n_links: u32,
        /// Entity id of a person.
        frame_person.fp_id: u32,
        /// x (m, SNGNN axes).
        frame_person.fp_x: f32,
        /// y (m, SNGNN axes).
        frame_person.fp_y: f32,
        /// Angle (rad, SNGNN convention −(π/2 + relative heading), not wrapped).
        frame_person.fp_a: f32,
        /// Backward difference of the robot-frame x per 0.2 s (m per SNGNN frame).
        frame_person.fp_vx: f32,
        /// Backward difference of the robot-frame y per 0.2 s.
        frame_person.fp_vy: f32,
        /// Backward difference of the relative heading per 0.2 s (rad, not wrapped).
        frame_person.fp_va: f32,
        /// Entity id of an object.
        frame_object.fo_id: u32,
        /// x (m, SNGNN axes).
        frame_object.fo_x: f32,
        /// y (m, SNGNN axes).
        frame_object.fo_y: f32,
        /// Angle (rad, SNGNN convention).
        frame_object.fo_a: f32,
        /// Backward difference of the robot-frame x per 0.2 s.
        frame_object.fo_vx: f32,
        /// Backward difference of the robot-frame y per 0.2 s.
        frame_object.fo_vy: f32,
        /// Backward difference of the relative heading per 0.2 s (rad).
        frame_object.fo_va: f32,
        /// Size along the object's x (m): laptop and table length, plant diameter.
        frame_object.fo_size_x: f32,
        /// Size along the object's y (m): laptop and table width, plant diameter.
        frame_object.fo_size_y: f32,
        /// Source entity id of an interaction entry.
        frame_link.fl_src: u32,
        /// Destination entity id of an interaction entry.
        frame_link.fl_dst: u32,
        /// Robot-frame x (m) of entity `id` (at index id − 1) at the end of the previous step.
        sngnn_entity.sn_prev_x: f32,
        /// Robot-frame y (m) at the end of the previous step.
        sngnn_entity.sn_prev_y: f32,
        /// Relative heading (rad, wrapped) at the end of the previous step.
        sngnn_entity.sn_prev_theta: f32,
    }
}

impl BatchState {
    /// A zeroed state for `n_envs` environments with capacities `caps`.
    pub fn new(n_envs: usize, caps: Caps) -> Self {
        Self::zeroed(n_envs, caps)
    }

    /// A zeroed state whose environment i will start its first episode with seed `seed` + i
    /// (wrapping), gymnasium's convention for vector environments.
    pub fn seeded(n_envs: usize, caps: Caps, seed: u64) -> Self {
        let mut s = Self::new(n_envs, caps);
        for e in 0..n_envs {
            s.set_next_seed(e, seed.wrapping_add(e as u64));
        }
        s
    }

    /// Give environment `e`'s next episode (the one its next reset starts) the seed `seed`, and
    /// restart its episode count.
    pub fn set_next_seed(&mut self, e: usize, seed: u64) {
        (self.next_seed_lo[e], self.next_seed_hi[e]) = crate::seeds::seed_words(seed);
        self.episode[e] = 0;
    }

    /// The seed of environment `e`'s current episode.
    pub fn episode_seed(&self, e: usize) -> u64 {
        crate::seeds::seed_from_words(self.seed_lo[e], self.seed_hi[e])
    }

    /// The seed environment `e`'s next episode will have.
    pub fn next_seed(&self, e: usize) -> u64 {
        crate::seeds::seed_from_words(self.next_seed_lo[e], self.next_seed_hi[e])
    }

    /// Deterministic fingerprint of the whole batch (every column, every environment).
    pub fn fingerprint(&self) -> u64 {
        (0..self.n_envs).fold(columns::FNV_OFFSET, |h, e| self.fingerprint_env(e, h))
    }
}
