//! Stage `autoreset` (`src/systems/autoreset.rs`, `shaders/autoreset.wgsl`): the three autoreset
//! modes through the public API (`cpu`) and CPU/GPU parity in each (`gpu`).

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
