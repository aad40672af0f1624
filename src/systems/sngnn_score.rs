//! Stage `sngnn_score`: the second half of SNGNN-v2's reward (docs/spec.md 6.3, 7.3-7.4). For every
//! environment the reward scores with its terms, the graph of the frames the history selects goes
//! through the network, and the room node's first output, unclipped, goes into the
//! `r_discomfort_sngnn` column, where the reward stage clips it to [0, 1]. A no-op unless the
//! reward is SNGNN-v2's.
//!
//! On the GPU this stage is the network's own shader (`shaders/sngnn_score.wgsl`, recorded by
//! `backend::gpu::GpuNet`) over the graphs stage `sngnn_graph` packed, and it writes the same
//! column, so the reward stage is one code path on both backends.

use crate::params::StepParams;
use crate::sngnn::{self, Scorer};
use crate::state::StateChunk;

use super::Batch;
use super::reward::{REWARD_SNGNN, clip_sngnn, scores_terms};

/// Score the step of environment `e` with SNGNN-v2.
#[expect(
    clippy::expect_used,
    reason = "BatchEnv gives a batch with the SNGNN-v2 reward its scorer"
)]
pub fn sngnn_score(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if p.reward_kind != REWARD_SNGNN || !scores_terms(b, e) {
        return;
    }
    let scorer = b
        .sngnn
        .expect("BatchEnv gives a batch with the SNGNN-v2 reward its scorer");
    b.s.r_discomfort_sngnn[e] = raw_score(p, &b.s, scorer, e);
}

/// SNGNN-v2's raw score of environment `e`'s recorded history: the room node's first output for
/// the graph of the selected frames (docs/spec.md 7.3-7.4), before the reward's clipping.
pub fn raw_score(p: &StepParams, s: &StateChunk, scorer: &Scorer, e: usize) -> f32 {
    let [q1, _] = scorer.score_with(|graph| {
        sngnn::graph::build(p, s, e, graph);
    });
    q1
}

/// SNGNN-v2's discomfort of this step in [0, 1], outside the step: what stages `sngnn_graph`,
/// `sngnn_score` and `reward` do to environment `e` with the network's output (the frame joins
/// the history, the graph is scored, the score clipped). For pictures of the reward over
/// positions ([`crate::heatmap`]).
pub fn discomfort(p: &StepParams, s: &mut StateChunk, scorer: &Scorer, e: usize) -> f32 {
    sngnn::frame::record(p, s, e);
    clip_sngnn(raw_score(p, s, scorer, e))
}
