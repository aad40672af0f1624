//! The stages of the step, one file each (named in [`crate::pipeline::STAGES`]), plus the shared
//! pieces they use: [`Batch`] (what a stage runs on), world queries, the ORCA glue, the social
//! force model and resets.

use crate::error::SimError;
use crate::outputs::OutChunk;
use crate::rng::{RngStream, stream_id};
use crate::seeds;
use crate::sngnn::Scorer;
use crate::state::StateChunk;

/// Everything a stage reads and writes for a contiguous range of environments.
#[derive(Debug)]
pub struct Batch<'a> {
    /// State of the environments.
    pub s: StateChunk<'a>,
    /// Their outputs.
    pub o: OutChunk<'a>,
    /// Their actions: 3 floats per environment in [-1, 1] (forward, lateral, rotation), already
    /// validated at the API boundary.
    pub actions: &'a [f32],
    /// The SNGNN-v2 scorer, when the reward is SNGNN-v2's (shared, read-only).
    pub sngnn: Option<&'a Scorer>,
    /// The first error a stage met (only resets can fail: an unsatisfiable scenario).
    pub error: Option<SimError>,
}

impl<'a> Batch<'a> {
    /// Split into the first `mid` environments and the rest.
    pub fn split_at(self, mid: usize) -> (Batch<'a>, Batch<'a>) {
        let (s0, s1) = self.s.split_at(mid);
        let (o0, o1) = self.o.split_at(mid);
        // Resets run without actions: both halves then get none.
        let (a0, a1) = if self.actions.is_empty() {
            (self.actions, self.actions)
        } else {
            self.actions.split_at(3 * mid)
        };
        (
            Batch {
                s: s0,
                o: o0,
                actions: a0,
                sngnn: self.sngnn,
                error: None,
            },
            Batch {
                s: s1,
                o: o1,
                actions: a1,
                sngnn: self.sngnn,
                error: self.error,
            },
        )
    }

    /// Number of environments.
    pub fn n_envs(&self) -> usize {
        self.s.n_envs
    }

    /// Batch index of local environment `e` (names it in errors; nothing random depends on it).
    pub fn env_index(&self, e: usize) -> u32 {
        (self.s.first_env + e) as u32
    }
}

/// The episode seed of environment `e` (every draw of its episode is keyed by it).
pub fn episode_seed(s: &StateChunk, e: usize) -> u64 {
    seeds::seed_from_words(s.seed_lo[e], s.seed_hi[e])
}

/// The random stream of kind `kind` for this step of environment `e`: keyed by the episode seed
/// and the tick, so draws never depend on other environments, on the environment's place in the
/// batch, on other stages or on the order of work.
pub fn step_stream(s: &StateChunk, e: usize, kind: u32) -> RngStream {
    RngStream::new(episode_seed(s, e), stream_id(kind, s.tick[e]))
}

/// [`step_stream`], keyed only when first drawn from: stages that draw only on rare occasions
/// (a goal reached, an event) skip hashing the key on every other step. The draws are the same.
pub struct LazyStream {
    key: (u64, u32),
    rng: Option<RngStream>,
}

impl LazyStream {
    /// The stream of kind `kind` for this step of environment `e`.
    pub fn new(s: &StateChunk, e: usize, kind: u32) -> Self {
        Self {
            key: (episode_seed(s, e), stream_id(kind, s.tick[e])),
            rng: None,
        }
    }

    /// The stream, keyed on the first call.
    #[inline]
    pub fn get(&mut self) -> &mut RngStream {
        let (seed, stream) = self.key;
        self.rng.get_or_insert_with(|| RngStream::new(seed, stream))
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
pub mod sngnn_graph;
pub mod sngnn_score;
pub mod social_events;
pub mod termination;
pub mod world;
