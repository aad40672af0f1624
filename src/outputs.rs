//! What a step hands back, per environment, in caller-visible buffers that are overwritten every
//! step (never reallocated): observation, per-type counts, reward, flags, info, the final
//! observation and info of SAME_STEP autoresets, and the statistics of finished episodes.

use crate::spec::{N_EPISODE, N_EVENTS, N_INFO, ObsLayout};
use crate::state::columns::soa;

/// Strides of the output columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutStrides {
    /// Observation layout.
    pub layout: ObsLayout,
}

impl OutStrides {
    /// One value per environment.
    pub fn env(&self) -> usize {
        1
    }
    /// Observation floats per environment.
    pub fn obs(&self) -> usize {
        self.layout.dim
    }
    /// Per-type record counts per environment.
    pub fn counts(&self) -> usize {
        5
    }
    /// Info values per environment.
    pub fn info(&self) -> usize {
        N_INFO
    }
    /// Episode statistics per environment.
    pub fn episode(&self) -> usize {
        N_EPISODE
    }
    /// Social event counts per environment.
    pub fn events(&self) -> usize {
        N_EVENTS
    }
}

soa! {
    /// Step outputs of a batch (see the module docs).
    pub struct Outputs / OutChunk over OutStrides {
        /// Observation (layout in [`crate::spec`]).
        obs.obs: f32,
        /// Real records per entity type in `obs` (order of [`crate::spec::ENTITY_KEYS`]).
        counts.obs_count: u32,
        /// Reward of the step.
        env.reward: f32,
        /// 1 if the episode terminated at this step.
        env.terminated: u32,
        /// 1 if the episode was truncated (timeout) at this step.
        env.truncated: u32,
        /// Info values (order of [`crate::spec::INFO_KEYS`]).
        info.info: f32,
        /// SAME_STEP: 1 when `final_obs`/`final_info` hold the finished episode's last step.
        env.has_final: u32,
        /// SAME_STEP: the observation of the finishing step.
        obs.final_obs: f32,
        /// SAME_STEP: per-type counts of `final_obs`.
        counts.final_obs_count: u32,
        /// SAME_STEP: the info of the finishing step.
        info.final_info: f32,
        /// 1 when an episode ended at this step and `episode` holds its statistics.
        env.episode_done: u32,
        /// Statistics of the episode that ended (order of [`crate::spec::EPISODE_KEYS`]).
        episode.episode: f32,
        /// Social events of this step (order of [`crate::spec::EVENT_KEYS`]).
        events.events: u32,
    }
}

impl Outputs {
    /// Zeroed outputs for `n_envs` environments with observation layout `layout`.
    pub fn new(n_envs: usize, layout: ObsLayout) -> Self {
        Self::zeroed(n_envs, OutStrides { layout })
    }
}
