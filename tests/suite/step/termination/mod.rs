//! Stage `termination` (`src/systems/termination.rs`, `shaders/termination.wgsl`): the outcome
//! flags, hand-computed (`cpu`), and CPU/GPU parity (`gpu`, whose perturbation `reward` and
//! `metrics` build on).

mod cpu;
#[cfg(feature = "gpu")]
pub(crate) mod gpu;
