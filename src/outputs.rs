//! What a step hands back, per environment, in caller-visible buffers that are overwritten every
//! step (never reallocated): observation, per-type counts, interaction pairs, reward, flags, info,
//! the final observation, interactions and info of SAME_STEP autoresets, and the statistics of
//! finished episodes.

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
    /// Human-human pair indices per environment (two per pair).
    pub fn hh(&self) -> usize {
        2 * self.layout.pairs[crate::spec::interaction::HUMAN_HUMAN]
    }
    /// Human-laptop pair indices per environment (two per pair).
    pub fn hl(&self) -> usize {
        2 * self.layout.pairs[crate::spec::interaction::HUMAN_LAPTOP]
    }
    /// Pair counts per environment, one per interaction kind.
    pub fn pairs(&self) -> usize {
        2
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
        /// Human-human interactions: pairs (i, j) of `humans` record indices, flattened
        /// `[i0, j0, i1, j1, ...]`, zero past `pair_count[0]` pairs.
        hh.hh_pairs: u32,
        /// Human-laptop interactions: pairs (`humans` index, `laptops` index), flattened, zero
        /// past `pair_count[1]` pairs.
        hl.hl_pairs: u32,
        /// Pairs per interaction kind (order of [`crate::spec::INTERACTION_KEYS`]).
        pairs.pair_count: u32,
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
        /// SAME_STEP: the human-human pairs of the finishing step.
        hh.final_hh_pairs: u32,
        /// SAME_STEP: the human-laptop pairs of the finishing step.
        hl.final_hl_pairs: u32,
        /// SAME_STEP: the pair counts of the finishing step.
        pairs.final_pair_count: u32,
        /// SAME_STEP: the info of the finishing step.
        info.final_info: f32,
        /// 1 when an episode ended at this step and `episode` holds its statistics.
        env.episode_done: u32,
        /// Statistics of the episode that ended (order of [`crate::spec::EPISODE_KEYS`]).
        episode.episode: f32,
        /// Low word of the seed of the episode that ended (with `episode_done`): the episode
        /// replays alone from it.
        env.episode_seed_lo: u32,
        /// High word of the seed of the episode that ended.
        env.episode_seed_hi: u32,
        /// Social events of this step (order of [`crate::spec::EVENT_KEYS`]).
        events.events: u32,
    }
}

/// The output columns a step writes only for an environment whose episode ends at it: the
/// SAME_STEP finals (with `has_final`) and the episode statistics and seed (with
/// `episode_done`). Every other column is written at every step. Between two such steps these
/// columns keep their values, on both backends, so a host copy needs them only from the
/// environments that finished (the GPU backend's step readback, `backend::gpu::readback`).
pub const FINISHED_ONLY_COLUMNS: [&str; 9] = [
    "final_obs",
    "final_obs_count",
    "final_hh_pairs",
    "final_hl_pairs",
    "final_pair_count",
    "final_info",
    "episode",
    "episode_seed_lo",
    "episode_seed_hi",
];

impl Outputs {
    /// Zeroed outputs for `n_envs` environments with observation layout `layout`.
    pub fn new(n_envs: usize, layout: ObsLayout) -> Self {
        Self::zeroed(n_envs, OutStrides { layout })
    }
}

/// The per-step output columns a caller can leave out of what a step delivers (each `true` by
/// default: every column delivered). The observation and its counts, the reward, the flags and
/// the finished-only columns of the environments that finished are always delivered.
///
/// A column left out is not kept current: the GPU backend does not read it back from the device
/// (fewer bytes a step: for exp2 with padded observations the interactions and the events are
/// a fifth of them, the info a seventh), so the host's copy keeps what it last held; the CPU
/// backend writes its outputs in place and keeps writing it. Read it only while it is selected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepOutputs {
    /// `info`: the step's metrics ([`crate::spec::INFO_KEYS`]).
    pub info: bool,
    /// `hh_pairs`, `hl_pairs` and `pair_count`: the interactions of the observation.
    pub interactions: bool,
    /// `events`: the social events of the step.
    pub events: bool,
}

impl Default for StepOutputs {
    fn default() -> Self {
        Self::ALL
    }
}

impl StepOutputs {
    /// Every per-step column.
    pub const ALL: Self = Self {
        info: true,
        interactions: true,
        events: true,
    };
    /// Only the columns always delivered (observation, counts, reward, flags).
    pub const LEAN: Self = Self {
        info: false,
        interactions: false,
        events: false,
    };
    /// The columns that can be left out, in output order.
    pub const OPTIONAL: [&'static str; 5] =
        ["hh_pairs", "hl_pairs", "pair_count", "info", "events"];

    /// Whether a step delivers output column `name` (the [`FINISHED_ONLY_COLUMNS`] are
    /// delivered for the environments that finished, always).
    pub fn delivers(&self, name: &str) -> bool {
        match name {
            "info" => self.info,
            "hh_pairs" | "hl_pairs" | "pair_count" => self.interactions,
            "events" => self.events,
            _ => true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::spec::ObsLayout;
    use crate::state::Caps;

    #[test]
    fn every_optional_column_is_a_per_step_output() {
        let config = Config::from_name_or_path("exp2").expect("a shipped config");
        let caps = Caps::from_config(&config);
        let out = Outputs::new(1, ObsLayout::new(&caps, &config.observation));
        let names: Vec<_> = out.columns().iter().map(|c| c.0).collect();
        for column in StepOutputs::OPTIONAL {
            assert!(names.contains(&column), "{column} is no output column");
            assert!(!FINISHED_ONLY_COLUMNS.contains(&column), "{column}");
            assert!(!StepOutputs::LEAN.delivers(column), "{column}");
            assert!(StepOutputs::ALL.delivers(column), "{column}");
        }
        for always in [
            "obs",
            "obs_count",
            "reward",
            "terminated",
            "truncated",
            "has_final",
        ] {
            assert!(StepOutputs::LEAN.delivers(always), "{always}");
        }
        let info_only = StepOutputs {
            info: true,
            ..StepOutputs::LEAN
        };
        assert!(info_only.delivers("info") && !info_only.delivers("hh_pairs"));
        let left_out: Vec<&str> = names
            .iter()
            .copied()
            .filter(|c| !StepOutputs::LEAN.delivers(c))
            .collect();
        assert_eq!(left_out, StepOutputs::OPTIONAL, "in output order");
    }
}
