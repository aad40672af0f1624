//! What users touch: the public API's errors, config validation, the command-line tool's
//! backends, the built-in policies, rendering, the heatmap figure, the SNGNN-v2 weight file, and the live viewer and its recordings.

mod api_errors;
#[cfg(all(feature = "gpu", feature = "cli"))]
mod cli_backends;
// The `socnav` binary's bad input; the binary needs the `cli` feature.
#[cfg(feature = "cli")]
mod cli_input;
mod config_validation;
// Faults caused on the GPU device: destroyed, too small for the batch.
#[cfg(feature = "gpu")]
mod gpu_faults;
// The heatmap tests run the `socnav` binary, which needs the `cli` feature.
#[cfg(feature = "cli")]
mod heatmap;
mod policies;
#[cfg(feature = "render")]
mod render;
mod sngnn_weights;
// `socnav play` and the recordings; the binary needs the `cli` feature.
#[cfg(feature = "cli")]
mod viewer;
