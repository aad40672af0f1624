//! Stage `shadow_robot` (`src/systems/shadow_robot.rs`, `shaders/shadow_robot.wgsl`): a
//! hand-computed collision (`cpu`) and CPU/GPU parity (`gpu`, whose harness `group_velocities`
//! shares).

mod cpu;
#[cfg(feature = "gpu")]
pub(crate) mod gpu;
