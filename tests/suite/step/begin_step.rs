//! CPU/GPU parity of stage `begin_step` (`src/systems/begin_step.rs`, `shaders/begin_step.wgsl`;
//! docs/spec.md, determinism): from the same state, parameters and actions, the shader must leave
//! the state and the outputs bit-identical to its Rust twin on lavapipe, on rolled-out states
//! perturbed before each run (the harness: `tests/common/gpu.rs`). [`scatter_ends`] serves
//! `autoreset` too.

use crate::common::gpu::*;
use socnav::StepParams;
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::state::BatchState;

/// Episodes ending, pending resets and stale per-step outputs at random: every branch of
/// `begin_step` and `autoreset`.
pub(crate) fn scatter_ends(
    s: &mut BatchState,
    o: &mut Outputs,
    _: &StepParams,
    rng: &mut RngStream,
) {
    for e in 0..s.n_envs {
        s.done[e] = u32::from(rng.next_f32() < 0.4);
        s.pending_reset[e] = u32::from(rng.next_f32() < 0.3);
        s.stepping[e] = u32::from(rng.next_f32() < 0.8);
        o.has_final[e] = u32::from(rng.next_f32() < 0.5);
        o.episode_done[e] = u32::from(rng.next_f32() < 0.5);
        o.reward[e] = uniform(rng, -1.0, 1.0);
        o.terminated[e] = s.done[e];
        for v in &mut o.events[e * socnav::spec::N_EVENTS..(e + 1) * socnav::spec::N_EVENTS] {
            *v = rng.next_u32() % 2;
        }
    }
}

/// Contract: `begin_step`: flags cleared, ticks counted, and NEXT_STEP resets copied from the
/// reset pool equal the CPU's in-place resets (state, first observation, zeroed info), each reset
/// run by one lane and by a workgroup's lanes (`GpuPaths::resets_in_workgroups`).
#[test]
fn begin_step() {
    for dev in devices_both_reset_ways() {
        for name in ["exp1", "exp3", "lroom_mixed"] {
            let mode = socnav::AutoresetMode::NextStep;
            let config = config(name);
            check_parity_on(
                dev.clone(),
                "begin_step",
                config,
                mode,
                256,
                10,
                Some(scatter_ends),
            );
        }
    }
}
