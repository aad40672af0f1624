//! Scripted policies for rollouts: uniform random actions, or a go-to-goal controller that reads
//! the goal from the observation's robot record (robot frame).

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use socnav::config::Kinematics;
use socnav::{BatchEnv, math};

use crate::args::PolicyChoice;

/// Chooses the actions of a batch.
pub struct Policy {
    choice: PolicyChoice,
    rng: StdRng,
    holonomic: bool,
}

impl Policy {
    pub fn new(choice: PolicyChoice, seed: u64, env: &BatchEnv) -> Self {
        let holonomic = env.config().robot.kinematics == Kinematics::Holonomic;
        // The policy's randomness is outside the simulation: a host RNG, seeded apart from the batch.
        Self {
            choice,
            rng: StdRng::seed_from_u64(seed ^ 0x5eed_0f90_11c7),
            holonomic,
        }
    }

    /// Fill `actions` (3 per environment) from the batch's current observations.
    pub fn act(&mut self, env: &BatchEnv, actions: &mut [f32]) {
        match self.choice {
            PolicyChoice::Random => {
                for a in actions.chunks_exact_mut(3) {
                    a[0] = self.rng.random_range(-1.0..=1.0);
                    a[1] = if self.holonomic {
                        self.rng.random_range(-1.0..=1.0)
                    } else {
                        0.0
                    };
                    a[2] = self.rng.random_range(-1.0..=1.0);
                }
            }
            PolicyChoice::Goal => {
                let out = env.outputs();
                let dim = env.layout().dim;
                let p = env.params();
                for (e, a) in actions.chunks_exact_mut(3).enumerate() {
                    let (gx, gy) = (out.obs[e * dim + 6], out.obs[e * dim + 7]);
                    let bearing = math::atan2(gy, gx);
                    // Turn by the bearing within one step, drive when within ~17° of it.
                    a[2] = (bearing / (p.robot_max_rotation * p.dt)).clamp(-1.0, 1.0);
                    a[0] = if bearing.abs() < 0.3 { 1.0 } else { 0.0 };
                    a[1] = 0.0;
                }
            }
        }
    }
}
