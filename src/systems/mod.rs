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
