//! socnav: a GPU-batched social-navigation simulator with SocNavGym 0.1.1 semantics.
//!
//! One [`BatchEnv`] steps thousands of environments at once. A step runs the stages of
//! [`pipeline::STAGES`] in the reference's order: actions and robot motion, the ORCA shadow
//! robot, group and human motion (ORCA, social force), goal re-sampling, formations, contacts,
//! termination, SNGNN-v2's frame and score (with that reward), reward, metrics, observation, the
//! social events, autoreset. The state is a structure of arrays
//! ([`state::BatchState`]) with fixed capacities taken from the config; randomness comes only
//! from a counter-based generator keyed by (episode seed, stream, draw), so the same seed and
//! actions give the same trajectory on any machine and thread count, and every episode replays
//! alone from its 64-bit episode seed.
//!
//! See `docs/ARCHITECTURE.md` for the code map and the invariants, `configs/README.md` for
//! every configuration key, `docs/fidelity.md` for every deviation from SocNavGym 0.1.1,
//! `docs/spec.md` for the specification the code cites and `docs/gpu-backend.md` for the GPU
//! backend's mechanisms.
//!
//! ```
//! use socnav::{Actions, BatchEnv, Config, EnvOptions};
//! let config = Config::default(); // the paper's experiment 1
//! let mut env = BatchEnv::new(config, EnvOptions { n_envs: 8, seed: 0, ..Default::default() }).unwrap();
//! env.reset(None).unwrap();
//! let actions = vec![0.5f32, 0.0, 0.1].repeat(8);
//! env.step(Actions::Continuous(&actions)).unwrap();
//! assert_eq!(env.outputs().reward.len(), 8);
//! ```

// A user's input never panics: every internal invariant that would is marked with
// `#[expect(clippy::..., reason = "...")]` saying why it holds (clippy.toml lets unit tests).
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

pub mod backend;
pub mod config;
pub mod document;
mod env;
pub mod episodes;
pub mod error;
pub mod fixed;
pub mod geometry;
pub mod heatmap;
pub mod limits;
pub mod math;
pub mod orca;
pub mod outputs;
pub mod params;
pub mod pipeline;
pub mod policies;
pub mod recording;
#[cfg(feature = "render")]
pub mod render;
pub mod rng;
pub mod room;
pub mod scenario;
pub mod seeds;
pub mod sngnn;
pub mod spec;
pub mod state;
pub mod systems;
#[cfg(feature = "viewer")]
pub mod viewer;

pub use config::Config;
pub use env::{Actions, BatchEnv, EnvOptions, MAX_THREADS};
pub use error::SimError;
pub use params::{AutoresetMode, StepParams};
