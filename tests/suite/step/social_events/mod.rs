//! Stage `social_events` (`src/systems/social_events.rs`, `shaders/social_events.wgsl`): the
//! events against SocNavGym 0.1.1's recordings and their configured rates (`cpu`), and CPU/GPU
//! parity (`gpu`, whose harness `formation` shares).

mod cpu;
#[cfg(feature = "gpu")]
pub(crate) mod gpu;
