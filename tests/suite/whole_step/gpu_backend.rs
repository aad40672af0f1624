//! The GPU backend outside the stages (DESIGN.md section 4): the state's and the outputs' trip to
//! the device and back, and the masked reset pass (`shaders/reset.wgsl`, the twin of
//! `CpuBackend::reset`) against the CPU's, bit for bit on lavapipe (the harness:
//! `tests/common/gpu.rs`).

use crate::common::gpu::*;
use socnav::backend::gpu::GpuStages;
use socnav::outputs::Outputs;
use socnav::state::BatchState;

/// The state and the outputs survive the trip to the device and back bit for bit, every column.
#[test]
fn state_round_trip() {
    let Some(dev) = device() else { return };
    let env = rolled_out(config("exp3"), 64, 60);
    let state = env.state().clone();
    let outputs = env.outputs().clone();
    let gpu = GpuStages::new(dev, env.params(), &state, &outputs, &[]).expect("GPU stages");
    let mut back = BatchState::zeroed(state.n_envs, state.strides);
    assert!(!state.differing_columns(&back).is_empty());
    gpu.download_state(&mut back).expect("readback");
    assert!(
        state.differing_columns(&back).is_empty(),
        "state columns changed on the way: {:?}",
        state.differing_columns(&back)
    );
    let mut back = Outputs::zeroed(outputs.n_envs, outputs.strides);
    assert!(!outputs.differing_columns(&back).is_empty());
    gpu.download_outputs(&mut back).expect("readback");
    assert!(
        outputs.differing_columns(&back).is_empty(),
        "output columns changed on the way: {:?}",
        outputs.differing_columns(&back)
    );
}

/// Contract: the masked reset pass (`shaders/reset.wgsl`) equals `CpuBackend::reset` over about
/// half the environments, chained so that reset environments reset again from their next row.
#[test]
fn masked_reset() {
    for name in ["exp2", "stress"] {
        check_parity("reset", config(name), 256, 6, None);
    }
}
