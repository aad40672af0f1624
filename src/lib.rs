//! socnav: a GPU-batched social-navigation simulator with SocNavGym 0.1.1 semantics.
//!
//! The crate is the core library: configuration, scenario generation, the batched
//! structure-of-arrays state, the stages of the step and the backends that run them.
//! See `docs/ARCHITECTURE.md` for the code map and the invariants.

pub mod math;
pub mod orca;
pub mod rng;
