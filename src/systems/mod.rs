//! The stages of the step, one file each (named in [`crate::pipeline::STAGES`]), plus the shared
//! pieces they use: world queries, the ORCA glue, the social force model and resets.

use crate::params::StepParams;
use crate::rng::{RngStream, stream_id};
use crate::state::StateChunk;

/// The random stream of kind `kind` for this step of environment `e` (batch index `env`): keyed by
/// the batch seed, the environment, its episode and the tick, so draws never depend on other
/// environments, other stages or the order of work.
pub fn step_stream(p: &StepParams, s: &StateChunk, e: usize, env: u32, kind: u32) -> RngStream {
    RngStream::new(p.seed(), env, s.episode[e], stream_id(kind, s.tick[e]))
}

/// [`step_stream`], keyed only when first drawn from: stages that draw only on rare occasions
/// (a goal reached, an event) skip hashing the key on every other step. The draws are the same.
pub struct LazyStream {
    key: (u64, u32, u32, u32),
    rng: Option<RngStream>,
}

impl LazyStream {
    /// The stream of kind `kind` for this step of environment `e` (batch index `env`).
    pub fn new(p: &StepParams, s: &StateChunk, e: usize, env: u32, kind: u32) -> Self {
        Self {
            key: (p.seed(), env, s.episode[e], stream_id(kind, s.tick[e])),
            rng: None,
        }
    }

    /// The stream, keyed on the first call.
    #[inline]
    pub fn get(&mut self) -> &mut RngStream {
        let (seed, env, episode, stream) = self.key;
        self.rng
            .get_or_insert_with(|| RngStream::new(seed, env, episode, stream))
    }
}

pub mod autoreset;
pub mod begin_step;
pub mod contacts;
pub mod formation;
pub mod goals;
pub mod group_motion;
pub mod group_velocities;
pub mod human_motion;
pub mod metrics;
pub mod observation;
pub mod orca_obstacles;
pub mod orca_world;
pub mod perception;
pub mod regroup;
pub mod reset;
pub mod reward;
pub mod robot_motion;
pub mod sfm;
pub mod shadow_robot;
pub mod social_events;
pub mod termination;
pub mod world;
