//! Stage `social_events` (`src/systems/social_events.rs`, `shaders/social_events.wgsl`): the
//! events against SocNavGym 0.1.1's recordings and their configured rates (`cpu`), and CPU/GPU
//! parity (`gpu`).

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
