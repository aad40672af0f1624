//! CPU/GPU parity of stage `robot_motion` (docs/spec.md, determinism): from the same state,
//! parameters and actions, `shaders/robot_motion.wgsl` must leave the state and the outputs
//! bit-identical to the Rust stage on lavapipe, over runs chained from rolled-out states (the
//! harness: `tests/common/gpu.rs`).

use crate::common::gpu::*;
use socnav::config::Kinematics;

/// Contract: `robot_motion` (diff-drive): command clipping, rotation first, then translation.
#[test]
fn robot_motion_diff_drive() {
    check_parity("robot_motion", config("exp1"), 256, 50, None);
}

/// Contract: `robot_motion` (holonomic): the lateral command and its θ + π/2 terms, with a time
/// step other than 1 s (at dt = 1 a misplaced factor of dt would go unseen).
#[test]
fn robot_motion_holonomic() {
    let mut c = config("exp2");
    c.robot.kinematics = Kinematics::Holonomic;
    c.episode.time_step = 0.3;
    check_parity("robot_motion", c, 256, 50, None);
}
