//! Scripted policies for rollouts: uniform random actions, the go-to-goal controller or the
//! ORCA-driven robot (`socnav::policies`).

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use socnav::config::Kinematics;
use socnav::policies::{self, OrcaRobot};
use socnav::{BatchEnv, SimError};

use crate::args::PolicyChoice;

/// Chooses the actions of a batch.
pub struct Policy {
    choice: PolicyChoice,
    rng: StdRng,
    holonomic: bool,
    orca: OrcaRobot,
}

impl Policy {
    pub fn new(choice: PolicyChoice, seed: u64, env: &BatchEnv) -> Self {
        let holonomic = env.config().robot.kinematics == Kinematics::Holonomic;
        // The policy's randomness is outside the simulation: a host RNG, seeded apart from the batch.
        Self {
            choice,
            rng: StdRng::seed_from_u64(seed ^ 0x5eed_0f90_11c7),
            holonomic,
            orca: OrcaRobot::new(),
        }
    }

    /// Fill `actions` (3 per environment) from the batch's current observations.
    pub fn act(&mut self, env: &BatchEnv, actions: &mut [f32]) -> Result<(), SimError> {
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
            PolicyChoice::Goal => policies::goal_actions(env, actions),
            PolicyChoice::Orca => return self.orca.actions(env, actions),
        }
        Ok(())
    }
}
