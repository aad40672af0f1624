//! CPU/GPU parity of stage `autoreset` (docs/spec.md, determinism): from the same state, parameters
//! and actions, `shaders/autoreset.wgsl` must leave the state and the outputs bit-identical to the
//! Rust stage on lavapipe, in each autoreset mode, on rolled-out states perturbed before each run
//! (the harness: `tests/common/gpu.rs`).

use crate::common::gpu::*;
use crate::step::begin_step::scatter_ends;
use socnav::AutoresetMode;

/// Contract: `autoreset` in each mode: SAME_STEP keeps the final observation, pairs and info
/// and resets from the pool keeping the step's reward and flags, each reset run by one lane and
/// by a workgroup's lanes (`GpuPaths::resets_in_workgroups`); NEXT_STEP marks the reset.
#[test]
fn autoreset() {
    for dev in devices_both_reset_ways() {
        for mode in [
            AutoresetMode::SameStep,
            AutoresetMode::NextStep,
            AutoresetMode::Disabled,
        ] {
            for name in ["exp2", "corridor_mixed"] {
                let config = config(name);
                check_parity_on(
                    dev.clone(),
                    "autoreset",
                    config,
                    mode,
                    256,
                    10,
                    Some(scatter_ends),
                );
            }
        }
    }
}
