//! Starting an episode: the state that every new episode begins with (after scenario
//! generation), and the reset of one environment inside a step (autoreset) or on request.

use crate::math;
use crate::params::StepParams;
use crate::scenario;
use crate::state::StateChunk;

use super::Batch;

/// When a reset builds the environment's ORCA obstacles (RVO2's `processObstacles` of its
/// polygons, the `ov_*` columns).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ObstacleBuild {
    /// In the reset, as every reset of the CPU backend does.
    #[default]
    Now,
    /// Later, by whoever copies the state: the reset leaves `obstacles_dirty` set and the
    /// obstacles empty (`n_obstacle_vertices` 0, every `ov_*` slot zero), so that a rebuild
    /// ([`super::orca_obstacles::rebuild_if_dirty`], or its WGSL twin after the GPU backend copies
    /// a reset-pool row) gives the bits [`ObstacleBuild::Now`] gives. The GPU backend's rows
    /// leave the build to the device where it asks for it (`GpuPaths::obstacles_after_resets`):
    /// the build is about two thirds of a row's instructions on the host (and those rows leave
    /// the obstacles' columns out altogether: `backend::wgsl::POOL_OBSTACLE_COLUMNS`).
    Deferred,
}

/// Initialise everything of environment `e` that is not drawn by the scenario: counters, robot
/// command, shadow robot, metric accumulators, reward memory, observation caches, the SNGNN frame
/// history, ORCA obstacles (built now or left to rebuild: `obstacles`).
pub fn init_episode(p: &StepParams, s: &mut StateChunk, e: usize, obstacles: ObstacleBuild) {
    s.tick[e] = 0;
    s.done[e] = 0;
    s.pending_reset[e] = 0;
    // No dynamics ran for this environment since its reset.
    s.stepping[e] = 0;
    s.robot_vx[e] = 0.0;
    s.robot_vy[e] = 0.0;
    s.robot_w[e] = 0.0;
    s.robot_wvx[e] = 0.0;
    s.robot_wvy[e] = 0.0;
    s.shadow_x[e] = s.robot_x[e];
    s.shadow_y[e] = s.robot_y[e];
    s.shadow_theta[e] = s.robot_theta[e];
    s.shadow_vx[e] = 0.0;
    s.shadow_vy[e] = 0.0;
    s.shadow_w[e] = 0.0;
    s.shadow_collided[e] = 0;
    s.shadow_reached[e] = 0;
    s.shadow_reach_tick[e] = 0;
    s.shadow_path_length[e] = 0.0;
    let dx = s.goal_x[e] - s.robot_x[e];
    let dy = s.goal_y[e] - s.robot_y[e];
    s.m_prev_goal_dist[e] = (dx * dx + dy * dy).sqrt();
    init_metrics(s, e);
    s.r_prev_dist[e] = 0.0;
    s.r_has_prev[e] = 0;
    s.r_discomfort_sngnn[e] = 0.0;
    s.r_discomfort_dsrnn[e] = 0.0;
    s.r_distance[e] = 0.0;
    s.r_alive[e] = 0.0;
    s.r_sngnn[e] = 0.0;
    super::formation::clear_crowd_formation(s, e);
    super::formation::clear_laptop_formation(s, e);
    let hb = e * s.strides.humans;
    let n = s.n_humans[e] as usize;
    for i in hb..hb + n {
        s.h_prev_rel_theta[i] = math::wrap_angle(s.h_theta[i] - s.robot_theta[e]);
        let (sn, c) = math::sin_cos(s.h_theta[i]);
        s.h_vx[i] = s.h_speed[i] * c;
        s.h_vy[i] = s.h_speed[i] * sn;
    }
    super::regroup::number_lists(s, e);
    crate::sngnn::frame::start_episode(s, e);
    s.obstacles_dirty[e] = 1;
    match obstacles {
        ObstacleBuild::Now => {
            // A generated scene's set always fits (`Caps`); the flag would say otherwise.
            super::orca_obstacles::rebuild_if_dirty(p, s, e);
        }
        ObstacleBuild::Deferred => super::orca_obstacles::clear(s, e),
    }
}

/// Metric accumulators of a new episode (docs/spec.md 8.2): minima start at +inf, the rest at 0.
fn init_metrics(s: &mut StateChunk, e: usize) {
    s.m_failure_to_progress[e] = 0;
    s.m_stalled_time[e] = 0.0;
    s.m_path_length[e] = 0.0;
    s.m_v_min[e] = f32::INFINITY;
    s.m_v_max[e] = 0.0;
    s.m_v_avg[e] = 0.0;
    s.m_prev_vx[e] = 0.0;
    s.m_prev_vy[e] = 0.0;
    s.m_a_min[e] = f32::INFINITY;
    s.m_a_max[e] = 0.0;
    s.m_a_avg[e] = 0.0;
    s.m_prev_ax[e] = 0.0;
    s.m_prev_ay[e] = 0.0;
    s.m_j_min[e] = f32::INFINITY;
    s.m_j_max[e] = 0.0;
    s.m_j_avg[e] = 0.0;
    s.m_compliant[e] = 0;
    init_episode_sums(s, e);
}

/// The per-episode sums and minima behind the episode statistics (docs/spec.md 8.3), at their
/// start.
pub fn init_episode_sums(s: &mut StateChunk, e: usize) {
    s.ep_return[e] = 0.0;
    s.ep_min_human_dist[e] = f32::INFINITY;
    s.ep_min_obstacle_dist[e] = f32::INFINITY;
    s.ep_sum_avg_obstacle_dist[e] = 0.0;
    s.ep_sum_ttc[e] = 0.0;
    s.ep_sum_discomfort_dsrnn[e] = 0.0;
    s.ep_sum_sngnn[e] = 0.0;
}

/// Reset environment `e` and write its first observation; reward 0, flags cleared, info zeroed.
pub fn reset_and_observe(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    reset_and_observe_building(p, b, e, ObstacleBuild::Now);
}

/// [`reset_and_observe`], its ORCA obstacles built as `obstacles` says (the observation does not
/// read them).
pub fn reset_and_observe_building(
    p: &StepParams,
    b: &mut Batch<'_>,
    e: usize,
    obstacles: ObstacleBuild,
) {
    b.o.reward[e] = 0.0;
    b.o.terminated[e] = 0;
    b.o.truncated[e] = 0;
    reset_building(p, b, e, obstacles);
}

/// Reset environment `e` and write its first observation and a zeroed info, keeping this step's
/// reward and flags (SAME_STEP autoreset returns those of the finishing step).
pub fn reset_and_observe_keep_step_outputs(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    reset_building(p, b, e, ObstacleBuild::Now);
}

/// [`reset_and_observe_keep_step_outputs`], its ORCA obstacles built as `obstacles` says.
fn reset_building(p: &StepParams, b: &mut Batch<'_>, e: usize, obstacles: ObstacleBuild) {
    let env_index = b.env_index(e);
    if let Err(err) = scenario::reset_env(p, &mut b.s, e, env_index) {
        b.s.done[e] = 1;
        b.error.get_or_insert(err);
        return;
    }
    init_episode(p, &mut b.s, e, obstacles);
    let info = b.o.strides.info();
    b.o.info[e * info..(e + 1) * info].fill(0.0);
    super::observation::write_observation(p, &mut b.s, &mut b.o, e);
}
