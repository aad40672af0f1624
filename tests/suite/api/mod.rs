//! What users touch: the public API's errors, config validation, the command-line tool's
//! backends, the built-in policies, rendering, the heatmap figure and the SNGNN-v2 weight file.

mod api_errors;
#[cfg(all(feature = "gpu", feature = "cli"))]
mod cli_backends;
mod config_validation;
// The heatmap tests run the `socnav` binary, which needs the `cli` feature.
#[cfg(feature = "cli")]
mod heatmap;
mod policies;
#[cfg(feature = "render")]
mod render;
mod sngnn_weights;
