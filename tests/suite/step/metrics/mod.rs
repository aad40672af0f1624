//! Stage `metrics` (`src/systems/metrics.rs`, `shaders/metrics.wgsl`): hand-computed metrics
//! (`cpu`) and CPU/GPU parity (`gpu`).

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
