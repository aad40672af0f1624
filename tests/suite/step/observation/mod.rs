//! Stage `observation` (`src/systems/observation/`, `shaders/observation.wgsl`): the records,
//! hand-computed (`cpu`); the observation options of 0.1.1's wrappers (`options`); and CPU/GPU
//! parity (`gpu`).

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
mod options;
