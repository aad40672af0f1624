//! Stage `sngnn_graph` (`src/systems/sngnn_graph.rs`, `src/sngnn/frame.rs` and `graph.rs`,
//! `shaders/sngnn_graph.wgsl`): SNGNN-v2's frames and graphs against SocNavGym 0.1.1's (`cpu`)
//! and the device's against the CPU's (`gpu`).

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
