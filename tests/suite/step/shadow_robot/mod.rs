//! Stage `shadow_robot` (`src/systems/shadow_robot.rs`, `shaders/shadow_robot.wgsl`): CPU/GPU
//! parity (`gpu`).

#[cfg(feature = "gpu")]
mod gpu;
