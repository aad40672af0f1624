//! Backends run the stages of [`crate::pipeline::STAGES`] over the batch. The CPU backend is the
//! reference; every backend must produce the same state, bit for bit, on a conforming device.

pub mod cpu;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod reset_pool;
pub mod wgsl;

use crate::error::SimError;
use crate::outputs::Outputs;
use crate::state::BatchState;

/// A way of running the step over the whole batch.
pub trait Backend: Send {
    /// Reset the environments whose `mask` entry is true (all when `mask` is `None`) and write
    /// their first observations.
    fn reset(&mut self, mask: Option<&[bool]>) -> Result<(), SimError>;
    /// Step every environment with `actions` (3 floats per environment, validated).
    fn step(&mut self, actions: &[f32]) -> Result<(), SimError>;
    /// The outputs of the last step or reset.
    fn outputs(&self) -> &Outputs;
    /// The batch state.
    fn state(&self) -> &BatchState;
    /// The batch state, for loading a snapshot; call [`Backend::state_changed`] afterwards.
    fn state_mut(&mut self) -> &mut BatchState;
    /// Re-derive what depends on a state edited through [`Backend::state_mut`] for environment
    /// `env` (ORCA obstacles, observation) without stepping.
    fn state_changed(&mut self, env: usize);
    /// Time each stage of the following steps (off by default: it costs two clock reads per stage
    /// and chunk).
    fn set_stage_timing(&mut self, on: bool);
    /// Seconds spent in each stage while timing was on (order of `STAGES`).
    fn stage_seconds(&self) -> Vec<f64>;
    /// Short name, e.g. "cpu".
    fn name(&self) -> &'static str;
}
