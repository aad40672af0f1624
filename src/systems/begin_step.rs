//! Stage `begin_step`: decide whether the environment steps at all. Under NEXT_STEP autoreset an
//! environment that finished at the previous step is reset here instead, and this step returns
//! its first observation with reward 0; under DISABLED a finished environment stays frozen, its
//! outputs unchanged, until the caller resets it. A stepping environment's tick is counted here,
//! first, as 0.1.1 does.

use crate::params::StepParams;

use super::Batch;

/// Clear the per-step output flags and pick the environments whose dynamics run this step.
pub fn begin_step(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    b.o.has_final[e] = 0;
    b.o.episode_done[e] = 0;
    let n = b.o.strides.events();
    b.o.events[e * n..(e + 1) * n].fill(0);
    if b.s.pending_reset[e] != 0 {
        b.s.stepping[e] = 0;
        super::reset::reset_and_observe(p, b, e);
    } else {
        b.s.stepping[e] = u32::from(b.s.done[e] == 0);
        // 0.1.1 counts the tick first: everything in the step sees the new tick.
        b.s.tick[e] += b.s.stepping[e];
    }
}
