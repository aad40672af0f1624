//! Stage `reward` (`src/systems/reward.rs`, `shaders/reward.wgsl`): the DSRNN reward and the
//! weighted terms, hand-computed (`cpu`), and CPU/GPU parity (`gpu`). The SNGNN-v2 reward's
//! clipping of the raw score is checked with the SNGNN-v2 stages (`sngnn_graph`).

mod cpu;
#[cfg(feature = "gpu")]
pub(crate) mod gpu;
