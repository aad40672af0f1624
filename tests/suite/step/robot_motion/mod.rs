//! Stage `robot_motion` (`src/systems/robot_motion.rs`, `shaders/robot_motion.wgsl`):
//! hand-computed kinematics (`cpu`) and CPU/GPU parity (`gpu`).

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
