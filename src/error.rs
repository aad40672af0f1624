//! The errors a user can cause. The core returns `Result<_, SimError>` for every such case and
//! panics only on broken internal invariants (with a message saying which); `clippy` denies
//! `unwrap`, `expect` and `panic!` outside tests, so each such invariant is marked where it is
//! relied on, with the reason it holds.
//!
//! Each variant carries what a caller would branch on as fields (the config key, the environment,
//! the argument or buffer, the I/O error's kind); its `Display` is the whole message.

use std::path::{Path, PathBuf};

/// Every error the simulator reports to its caller.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The configuration is invalid; every problem found is listed.
    #[error("invalid configuration:\n  - {}", list(.0))]
    Config(Vec<ConfigProblem>),
    /// Environment `env`'s scenario could not be generated: no free spot was found for `entity`
    /// (the room is too crowded for the configured counts and sizes).
    #[error("cannot generate a scenario: {message}")]
    Scenario {
        /// The environment whose reset failed.
        env: usize,
        /// What could not be placed ("a laptop user", "the robot's goal", ...).
        entity: String,
        /// The whole explanation.
        message: String,
    },
    /// An argument, array or state document (`what`) has the wrong shape, size or content.
    #[error("{message}")]
    Shape {
        /// The argument or buffer at fault ("reset mask", "state document", "render", ...).
        what: &'static str,
        /// The whole explanation, naming the bad value.
        message: String,
    },
    /// An environment index is outside the batch.
    #[error("environment index {env} out of range 0..{n_envs}")]
    EnvIndex {
        /// The index given.
        env: usize,
        /// The batch's size.
        n_envs: usize,
    },
    /// An action is invalid (not finite, wrong length, out of the discrete range).
    #[error("invalid action: {message}")]
    Action {
        /// The environment whose action is bad; `None` when the batch's array as a whole is
        /// (its length).
        env: Option<usize>,
        /// The whole explanation, naming the bad value.
        message: String,
    },
    /// The requested backend cannot run here (no adapter, or the batch exceeds its limits).
    #[error("backend unavailable: {0}")]
    BackendUnavailable(String),
    /// The device failed during a run (lost, a failed transfer). The batch's state on the device
    /// is then unknown: every later call on the batch reports the failure again; drop the batch
    /// and make a new one (a new batch opens a new device when the old one was lost).
    #[error("device failure: {0}")]
    Device(String),
    /// The host or the GPU cannot hold what was asked for (a batch too large for the machine's
    /// memory, or for the adapter's memory or largest binding); nothing of the new batch is kept,
    /// and batches made before it are unaffected.
    #[error("{message}")]
    OutOfMemory {
        /// The bytes asked for.
        bytes: u64,
        /// The GPU adapter that refused them; `None` for the host's memory.
        device: Option<String>,
        /// The whole explanation, with the batch size and what to do.
        message: String,
    },
    /// A call that does not fit the object it was made on (a low-level API used out of order, or
    /// on an object built without what the call needs).
    #[error("{0}")]
    Usage(String),
    /// A bug in socnav: an internal invariant broke during a call (a worker thread's panic,
    /// caught at the batch's boundary). The batch's state is unknown: drop it, and please report
    /// the message.
    #[error("internal error (a bug in socnav; please report it): {0}")]
    Internal(String),
    /// No window can be opened (no display, or the display refused it).
    #[error("cannot open a window: {0}")]
    Display(String),
    /// Reading or writing a file failed; `kind` is the operating system's error kind.
    #[error("{message}")]
    Io {
        /// The file or directory, when there is one.
        path: Option<PathBuf>,
        /// The kind of the underlying error (not found, permission denied, storage full, ...).
        kind: std::io::ErrorKind,
        /// The whole explanation, naming the file.
        message: String,
    },
    /// The SNGNN-v2 weights are missing or invalid; the message names the file and every
    /// problem found (a bad tensor, shape or value), or says how to install the weights.
    #[error("SNGNN-v2 weights: {0}")]
    Sngnn(String),
}

/// One problem of a configuration: its message, and the first key it names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigProblem {
    /// The dotted key the problem is about (`"robot.max_speed"`), when the message names one: the
    /// first `` `section.key` `` it quotes (a problem between keys names them all in the message).
    pub key: Option<String>,
    /// The whole explanation, naming the key and the offending value.
    pub message: String,
}

impl ConfigProblem {
    /// A problem from its message; the key is the first quoted `` `section.key` `` in it.
    pub fn new(message: impl Into<String>) -> Self {
        let message = message.into();
        let key = message
            .split('`')
            .skip(1)
            .step_by(2)
            .find(|k| {
                k.split_once('.').is_some_and(|(s, k)| {
                    !s.is_empty() && !k.is_empty() && !k.contains(' ') && !s.contains(' ')
                })
            })
            .map(str::to_owned);
        Self { key, message }
    }
}

impl std::fmt::Display for ConfigProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

fn list(problems: &[ConfigProblem]) -> String {
    let lines: Vec<&str> = problems.iter().map(|p| p.message.as_str()).collect();
    lines.join("\n  - ")
}

impl SimError {
    /// A configuration error from its problems' messages.
    pub fn config<S: Into<String>>(problems: impl IntoIterator<Item = S>) -> Self {
        SimError::Config(problems.into_iter().map(ConfigProblem::new).collect())
    }

    /// A shape error about `what`.
    pub fn shape(what: &'static str, message: impl Into<String>) -> Self {
        SimError::Shape {
            what,
            message: message.into(),
        }
    }

    /// An action error, about environment `env` when one is at fault.
    pub fn action(env: Option<usize>, message: impl Into<String>) -> Self {
        SimError::Action {
            env,
            message: message.into(),
        }
    }

    /// An I/O error of `path`: "`doing` PATH: the OS error", keeping the error's kind.
    pub fn io(doing: &str, path: &Path, e: &std::io::Error) -> Self {
        SimError::Io {
            path: Some(path.to_owned()),
            kind: e.kind(),
            message: format!("{doing} {}: {e}", path.display()),
        }
    }

    /// An I/O error without a file of its own (an encoder's failure while writing `path`), of
    /// kind `Other` unless the cause says otherwise.
    pub fn io_other(path: Option<&Path>, message: impl Into<String>) -> Self {
        SimError::Io {
            path: path.map(Path::to_owned),
            kind: std::io::ErrorKind::Other,
            message: message.into(),
        }
    }

    /// The configuration's problems, each as a string (empty for other errors).
    pub fn config_problems(&self) -> Vec<String> {
        match self {
            SimError::Config(problems) => problems.iter().map(|p| p.message.clone()).collect(),
            _ => Vec::new(),
        }
    }

    /// Prefix a configuration error with the file it came from.
    pub fn in_file(self, path: &Path) -> Self {
        match self {
            SimError::Config(problems) => SimError::Config(
                problems
                    .into_iter()
                    .map(|p| ConfigProblem {
                        key: p.key,
                        message: format!("{}: {}", path.display(), p.message),
                    })
                    .collect(),
            ),
            other => other,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_problem_names_the_first_key_it_quotes() {
        let p = ConfigProblem::new("`robot.max_speed` 9 m/s over `episode.time_step` 1 s ...");
        assert_eq!(p.key.as_deref(), Some("robot.max_speed"));
        let p = ConfigProblem::new("room too small: `a b` then `room.size_x` minimum 3");
        assert_eq!(p.key.as_deref(), Some("room.size_x"));
        assert_eq!(ConfigProblem::new("at most 64 humans").key, None);
    }

    #[test]
    fn an_io_error_keeps_its_kind_and_names_the_file() {
        let e = std::io::Error::from(std::io::ErrorKind::PermissionDenied);
        let err = SimError::io("cannot write", Path::new("out/x.png"), &e);
        let SimError::Io { kind, path, .. } = &err else {
            panic!("{err:?}")
        };
        assert_eq!(*kind, std::io::ErrorKind::PermissionDenied);
        assert_eq!(path.as_deref(), Some(Path::new("out/x.png")));
        assert!(err.to_string().starts_with("cannot write out/x.png: "));
    }
}
