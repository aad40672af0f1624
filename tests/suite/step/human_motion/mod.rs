//! Stage `human_motion` (`src/systems/human_motion.rs`, `shaders/human_motion.wgsl`): the speed
//! threshold, hand-computed (`cpu`); the humans' field of view (`perception`:
//! `src/systems/perception.rs` and `shaders/common/perception.wgsl`, which decide what each
//! walker of `human_motion` takes into account); and CPU/GPU parity (`gpu`).

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
mod perception;
