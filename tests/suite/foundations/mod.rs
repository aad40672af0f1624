//! The pieces under everything: the counter-based random streams (`src/rng.rs`), the accuracy of
//! `socnav::math`, the device's element order, the shaders' validation and the parts generated
//! into them, the crate's module graph and its files' lengths.

mod element_order;
mod file_sizes;
mod math_accuracy;
mod module_graph;
mod rng;
mod shaders_validate;
