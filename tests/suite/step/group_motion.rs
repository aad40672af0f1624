//! CPU/GPU parity of stage `group_motion` (`src/systems/group_motion.rs`,
//! `shaders/group_motion.wgsl`; docs/spec.md, determinism): from the same state, parameters and
//! actions, the shader must leave the state and the outputs bit-identical to its Rust twin on
//! lavapipe, over runs chained from rolled-out states (the harness: `tests/common/gpu.rs`).

use crate::common::gpu::*;

/// Contract: `group_motion`: moving groups walk with their (divided) velocity plus Gaussian
/// noise from the counter-based stream (experiment 2's groups have none: the noisy L room's do),
/// and their centres follow; replayed noise when the config asks for it.
#[test]
fn group_motion() {
    for name in ["exp2", "exp3", "lroom_mixed", "corridor_mixed"] {
        check_parity("group_motion", config(name), 256, 30, None);
    }
    let mut c = config("lroom_mixed");
    c.episode.time_step = 0.3;
    check_parity("group_motion", c, 256, 30, None);
}
