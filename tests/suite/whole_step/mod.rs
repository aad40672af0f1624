//! The step and the reset as a whole: CPU/GPU parity of whole trajectories (`cpu_gpu_parity`),
//! the GPU batch layout (`gpu_layout`), the GPU backend outside the stages (`gpu_backend`: the
//! state's trip to the device and back, the masked reset pass), determinism, episode seeds
//! (`episode_seeds`), generated scenarios
//! (`scenario_props`) and the reset pool, and properties checked on the golden episodes
//! (`golden_conditioning`, `golden_perturbed`, `fidelity_regressions`).

#[cfg(feature = "gpu")]
mod cpu_gpu_parity;
mod determinism;
mod episode_seeds;
mod fidelity_regressions;
mod golden_conditioning;
mod golden_perturbed;
#[cfg(feature = "gpu")]
mod gpu_backend;
#[cfg(feature = "gpu")]
mod gpu_layout;
mod invariants;
mod reset_pool;
mod scenario_props;
