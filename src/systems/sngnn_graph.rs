//! Stage `sngnn_graph`: the first half of SNGNN-v2's reward (docs/spec.md 6.3, 7.2). For every
//! environment the reward scores with its terms (it steps and the step is not terminal), the
//! step's frame joins the environment's history ([`sngnn::frame::record`]). A no-op unless the
//! reward is SNGNN-v2's.
//!
//! The shader (`shaders/sngnn_graph.wgsl`) also builds the graph of the selected frames into the
//! environment's packed graph buffers, where the network of the next stage reads it; on the CPU
//! the scorer builds it into its own scratch graph (stage `sngnn_score`), so the graph has no
//! storage between the two stages.

use crate::params::StepParams;
use crate::sngnn;

use super::Batch;
use super::reward::{REWARD_SNGNN, scores_terms};

/// Record the step's SNGNN-v2 frame of environment `e`.
pub fn sngnn_graph(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if p.reward_kind != REWARD_SNGNN || !scores_terms(b, e) {
        return;
    }
    sngnn::frame::record(p, &mut b.s, e);
}
