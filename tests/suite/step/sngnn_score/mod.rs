//! Stage `sngnn_score` (`src/systems/sngnn_score.rs`, `src/sngnn/model.rs` and `pieces.rs`,
//! `shaders/sngnn_score.wgsl`): SNGNN-v2 inference, tables against edge networks and the recorded
//! outputs (`cpu`), and the network on the device against the CPU's (`gpu`).

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
