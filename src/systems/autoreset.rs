//! Stage `autoreset`: what happens to an environment whose episode ended at this step.
//! SAME_STEP keeps the final observation, interactions and info aside and resets at once; NEXT_STEP marks the
//! environment so that `begin_step` resets it at the next step; DISABLED leaves it to the caller.

use crate::params::{AutoresetMode, StepParams};

use super::Batch;

/// Apply the batch's autoreset mode to an environment that finished at this step.
pub fn autoreset(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 || b.s.done[e] == 0 {
        return;
    }
    if p.autoreset == AutoresetMode::SameStep.code() {
        let (obs, info, counts) = (b.o.strides.obs(), b.o.strides.info(), b.o.strides.counts());
        b.o.final_obs[e * obs..(e + 1) * obs].copy_from_slice(&b.o.obs[e * obs..(e + 1) * obs]);
        b.o.final_info[e * info..(e + 1) * info]
            .copy_from_slice(&b.o.info[e * info..(e + 1) * info]);
        b.o.final_obs_count[e * counts..(e + 1) * counts]
            .copy_from_slice(&b.o.obs_count[e * counts..(e + 1) * counts]);
        let (hh, hl, pairs) = (b.o.strides.hh(), b.o.strides.hl(), b.o.strides.pairs());
        b.o.final_hh_pairs[e * hh..(e + 1) * hh]
            .copy_from_slice(&b.o.hh_pairs[e * hh..(e + 1) * hh]);
        b.o.final_hl_pairs[e * hl..(e + 1) * hl]
            .copy_from_slice(&b.o.hl_pairs[e * hl..(e + 1) * hl]);
        b.o.final_pair_count[e * pairs..(e + 1) * pairs]
            .copy_from_slice(&b.o.pair_count[e * pairs..(e + 1) * pairs]);
        b.o.has_final[e] = 1;
        super::reset::reset_and_observe_keep_step_outputs(p, b, e);
    } else if p.autoreset == AutoresetMode::NextStep.code() {
        b.s.pending_reset[e] = 1;
    }
}
