//! Built-in robot policies over a whole batch, shared by the command line and the Python package
//! (`socnav.policies`): the go-to-goal controller and the ORCA-driven robot. Both write
//! continuous actions in [-1, 1] (3 per environment: forward, lateral, rotation) for the batch's
//! current step; random actions are the caller's (a host RNG, outside the simulation).

use crate::config::ObsFrame;
use crate::error::SimError;
use crate::state::BatchState;
use crate::systems::orca_world::{self, Others};
use crate::systems::robot_motion;
use crate::systems::shadow_robot::command_from_velocity;
use crate::{BatchEnv, math};

/// Bearing (rad) within which the goal controller drives forward: about 17°.
const DRIVE_BEARING: f32 = 0.3;

/// The go-to-goal controller: turn toward the goal within one step, drive at full speed once it
/// is within about 17° of it. It reads the goal from the observation's robot record (robot or
/// world frame), so it costs nothing on any backend; it ignores every obstacle and human.
pub fn goal_actions(env: &BatchEnv, actions: &mut [f32]) {
    let out = env.outputs();
    let dim = env.layout().dim;
    let p = env.params();
    let world = env.config().observation.frame == ObsFrame::World;
    for (e, a) in actions.chunks_exact_mut(3).enumerate() {
        let r = &out.obs[e * dim..];
        let (gx, gy) = if world {
            // [one-hot(6), goal x, goal y, x, y, sin θ, cos θ, ...]: into the robot frame.
            let (dx, dy, sn, c) = (r[6] - r[8], r[7] - r[9], r[10], r[11]);
            (c * dx + sn * dy, c * dy - sn * dx)
        } else {
            (r[6], r[7])
        };
        let bearing = math::atan2(gy, gx);
        a[0] = if bearing.abs() < DRIVE_BEARING {
            1.0
        } else {
            0.0
        };
        a[1] = 0.0;
        a[2] = (bearing / (p.robot_max_rotation * p.dt)).clamp(-1.0, 1.0);
    }
}

/// The ORCA-driven robot: each step the robot takes the velocity ORCA gives it toward its goal at
/// full speed among every human, moving group and obstacle of its environment (the simulator the
/// shadow robot of the STL/SPL metrics uses, with the robot's own radius and velocity), mapped to
/// its drive as the shadow robot maps it. It reads the state, which the GPU backend downloads
/// for it at every step.
#[derive(Debug, Default)]
pub struct OrcaRobot {
    /// A copy of the batch state (so the policy needs no mutable access to the batch), reused
    /// across steps.
    scratch: Option<BatchState>,
}

impl OrcaRobot {
    /// A policy for any batch.
    pub fn new() -> Self {
        Self::default()
    }

    /// The actions of every environment of `env` at its current step.
    ///
    /// # Errors
    /// `SimError::Device` when a GPU batch's state cannot be downloaded.
    pub fn actions(&mut self, env: &BatchEnv, actions: &mut [f32]) -> Result<(), SimError> {
        let p = *env.params();
        let scratch = match &mut self.scratch {
            Some(s) if s.n_envs == env.n_envs() && s.strides == *env.caps() => s,
            slot => slot.insert(BatchState::new(env.n_envs(), *env.caps())),
        };
        scratch.clone_from(env.state()?);
        let s = scratch.chunk();
        let others = Others {
            skip_human: None,
            skip_group: None,
            robot: false,
            view: None,
        };
        for (e, a) in actions.chunks_exact_mut(3).enumerate() {
            let (x, y, theta) = (s.robot_x[e], s.robot_y[e], s.robot_theta[e]);
            let pref = orca_world::preferred(x, y, s.goal_x[e], s.goal_y[e], p.robot_max_speed);
            let vel = robot_motion::robot_world_velocity(&s, e);
            let agent = orca_world::agent(&s, e, [x, y], [vel.0, vel.1], pref, p.robot_radius);
            let v = orca_world::with_world(|w| w.velocity(&p, &s, e, &agent, others));
            let (vx, vy, w) = command_from_velocity(&p, theta, v[0], v[1]);
            // A robot that cannot move or turn (a limit of 0) is given 0, not 0 / 0.
            let scaled = |v: f32, max: f32| if max > 0.0 { v / max } else { 0.0 };
            a[0] = scaled(vx, p.robot_max_speed);
            a[1] = scaled(vy, p.robot_max_speed);
            a[2] = scaled(w, p.robot_max_rotation);
        }
        Ok(())
    }
}
