//! Stage `human_motion` (`src/systems/human_motion.rs`, `shaders/human_motion.wgsl`): the
//! humans' field of view (`perception`: `src/systems/perception.rs` and
//! `shaders/common/perception.wgsl`, which only `human_motion` uses) and CPU/GPU parity (`gpu`).

#[cfg(feature = "gpu")]
mod gpu;
mod perception;
