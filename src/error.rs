//! The errors a user can cause. The core returns `Result<_, SimError>` for every such case and
//! panics only on broken internal invariants (with a message saying which).

use std::path::Path;

/// Every error the simulator reports to its caller.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The configuration is invalid; every problem found is listed.
    #[error("invalid configuration:\n  - {}", .0.join("\n  - "))]
    Config(Vec<String>),
    /// A scenario could not be generated (e.g. the room is too crowded for the rejection sampler).
    #[error("cannot generate a scenario: {0}")]
    Scenario(String),
    /// An array or state document has the wrong shape, size or content.
    #[error("{0}")]
    Shape(String),
    /// An action is invalid (not finite, wrong length, out of the discrete range).
    #[error("invalid action: {0}")]
    Action(String),
    /// The requested backend cannot run here.
    #[error("backend unavailable: {0}")]
    BackendUnavailable(String),
    /// No window can be opened (no display, or the display refused it).
    #[error("cannot open a window: {0}")]
    Display(String),
    /// Reading or writing a file failed.
    #[error("{0}")]
    Io(String),
    /// The SNGNN-v2 weights are missing or invalid; the message names the file and every
    /// problem found (a bad tensor, shape or value), or says how to install the weights.
    #[error("SNGNN-v2 weights: {0}")]
    Sngnn(String),
}

impl SimError {
    /// Prefix a configuration error with the file it came from.
    pub fn in_file(self, path: &Path) -> Self {
        match self {
            SimError::Config(problems) => SimError::Config(
                problems
                    .into_iter()
                    .map(|p| format!("{}: {p}", path.display()))
                    .collect(),
            ),
            other => other,
        }
    }
}
