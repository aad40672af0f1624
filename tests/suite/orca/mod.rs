//! ORCA itself, not a stage: `src/orca/` (RVO2 2.0.3's algorithm) against the RVO2 reference
//! data (`reference`), its WGSL twin `shaders/common/orca.wgsl` on the device against the Rust
//! core (`gpu`), and the regression cases of the issues it had.

#[cfg(feature = "gpu")]
mod gpu;
mod issue_001_lp3_obstacle_line_failure;
mod reference;
