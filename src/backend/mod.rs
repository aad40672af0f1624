//! Backends run the stages of [`crate::pipeline::STAGES`] over the batch. The CPU backend is the
//! reference; every backend must produce the same state, bit for bit, on a conforming device.

pub mod cpu;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod obs_payload;
pub mod reset_pool;
pub mod schedule;
pub mod wgsl;

use crate::error::SimError;
use crate::outputs::Outputs;
use crate::params::StepParams;
use crate::sngnn::SngnnReward;
use crate::state::BatchState;

/// Which backend runs a batch (docs/spec.md, adapters).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum BackendChoice {
    /// The CPU backend.
    #[default]
    Cpu,
    /// The GPU backend on any adapter, software ones included (`WGPU_ADAPTER_NAME` and
    /// `WGPU_BACKEND` pick one); an error when there is none.
    Gpu,
    /// A hardware GPU adapter when one exists, else the CPU backend with one log line on stderr.
    Auto,
}

impl std::str::FromStr for BackendChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "cpu" => Ok(Self::Cpu),
            "gpu" => Ok(Self::Gpu),
            "auto" => Ok(Self::Auto),
            other => Err(format!(
                "unknown backend {other:?}: expected \"auto\", \"cpu\" or \"gpu\""
            )),
        }
    }
}

/// Open the backend `choice` names over `state` and `out`; `sngnn` scores the steps when the
/// reward is SNGNN-v2's.
///
/// # Errors
/// `BackendUnavailable` for `Gpu` without a usable adapter (the message says how to install a
/// driver) or in a build without the `gpu` feature, and for a batch the adapter cannot run
/// (an SNGNN-v2 time step without an exact frame rule on the device); `OutOfMemory` for a batch
/// too large for the adapter. `Auto` takes the CPU backend instead, with one line on stderr, in
/// each of these cases.
pub fn open(
    choice: BackendChoice,
    params: StepParams,
    state: BatchState,
    out: Outputs,
    threads: Option<usize>,
    sngnn: Option<SngnnReward>,
) -> Result<Box<dyn Backend>, SimError> {
    let on_cpu = |why: &str, state, out| -> Result<Box<dyn Backend>, SimError> {
        if !why.is_empty() {
            eprintln!("socnav: {why}; using the CPU backend");
        }
        let cpu = cpu::CpuBackend::new(params, state, out, threads)?;
        Ok(Box::new(
            cpu.with_sngnn(sngnn.as_ref().map(|r| r.scorer.clone())),
        ))
    };
    match choice {
        BackendChoice::Cpu => on_cpu("", state, out),
        #[cfg(feature = "gpu")]
        BackendChoice::Gpu | BackendChoice::Auto => {
            let policy = if choice == BackendChoice::Gpu {
                gpu::AdapterPolicy::Any
            } else {
                gpu::AdapterPolicy::Hardware
            };
            let dev = match gpu::GpuDevice::open(policy) {
                Ok(dev) => dev,
                Err(SimError::BackendUnavailable(why)) if choice == BackendChoice::Auto => {
                    return on_cpu(&why, state, out);
                }
                Err(e) => return Err(e),
            };
            // `Auto` falls back to the CPU when the adapter cannot run this batch either.
            let kept = (choice == BackendChoice::Auto).then(|| (state.clone(), out.clone()));
            match gpu::GpuBackend::new(dev, params, state, out, threads, sngnn.as_ref()) {
                Ok(gpu) => Ok(Box::new(gpu)),
                Err(
                    e @ (SimError::BackendUnavailable(_)
                    | SimError::OutOfMemory {
                        device: Some(_), ..
                    }),
                ) => match kept {
                    Some((state, out)) => on_cpu(&e.to_string(), state, out),
                    None => Err(e),
                },
                Err(e) => Err(e),
            }
        }
        #[cfg(not(feature = "gpu"))]
        BackendChoice::Gpu => Err(SimError::BackendUnavailable(
            "this build has no GPU backend (socnav was built without the `gpu` feature)".into(),
        )),
        #[cfg(not(feature = "gpu"))]
        BackendChoice::Auto => on_cpu("built without the `gpu` feature", state, out),
    }
}

/// Where a GPU batch's host path spends its time and what it moves, summed over every step and
/// reset since the batch was made (`socnav bench --backend gpu` reports it per step).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HostPath {
    /// Steps and resets that read their outputs back.
    pub reads: u64,
    /// Bytes copied from the device to host-visible memory.
    pub bytes: u64,
    /// Rows of environments that finished, read back with their step.
    pub finished_rows: u64,
    /// Reads that needed a second copy: more environments finished than the first copy held.
    pub second_reads: u64,
    /// Reads of the whole output table (after device work that was not read back).
    pub full_reads: u64,
    /// Seconds of reset-pool work on the critical path: generating the rows of the next episodes
    /// that are missing before a submit (normally none) and handing them to the device.
    pub refill_s: f64,
    /// Seconds generating reset-pool rows while the device runs a step (the rows two episodes
    /// ahead of the environments that reset) and handing them to the device (one queue write to
    /// a staging buffer, copied into place at the next submit): off the critical path unless
    /// longer than the device's work.
    pub refill_ahead_s: f64,
    /// Rows generated while the device ran a step (`refill_ahead_s`'s work).
    pub ahead_rows: u64,
    /// Seconds from submitting the device work to its readback being mapped, less the host's
    /// work meanwhile (`refill_ahead_s`).
    pub wait_s: f64,
    /// Of `wait_s`, the seconds recording and submitting the work (the step's passes and the
    /// readback's copies): the step's submit before the rows ahead, the readback's other pieces
    /// after them. Where a driver holds a submit until the one before it has finished (lavapipe
    /// does), this includes the rest of the step's passes.
    pub submit_s: f64,
    /// Seconds copying the mapped readback into the host's outputs.
    pub copy_s: f64,
    /// Reads timed on the device's clock (`Backend::set_step_timeline`).
    pub timed_reads: u64,
    /// Of those, the reads whose readback copies were timed too (the adapter writes timestamps
    /// between commands).
    pub timed_copies: u64,
    /// Seconds of the timed reads' passes on the device's clock. (They run while the host waits
    /// and makes the rows ahead: compare the device's part of a step with `wait_s`,
    /// `refill_ahead_s` and `copy_s` together.)
    pub device_s: f64,
    /// Seconds from the start of the step's commands to its passes (the reset pool's new rows
    /// copied into place, the queue counters cleared), on the device's clock, over the reads
    /// whose copies were timed.
    pub before_passes_s: f64,
    /// Seconds from the end of the passes to the end of the last readback copy, idle time
    /// between the readback's submits included, on the device's clock, over the reads whose
    /// copies were timed.
    pub readback_s: f64,
}

/// A way of running the step over the whole batch.
pub trait Backend: Send + Sync {
    /// Reset the environments whose `mask` entry is true (all when `mask` is `None`), clearing
    /// their pending resets, and write their first observations.
    fn reset(&mut self, mask: Option<&[bool]>) -> Result<(), SimError>;
    /// Step every environment with `actions` (3 floats per environment, validated).
    fn step(&mut self, actions: &[f32]) -> Result<(), SimError>;
    /// The outputs of the last step or reset.
    fn outputs(&self) -> &Outputs;
    /// The batch state (`SimError::Device` when the GPU backend's download of it fails).
    fn state(&self) -> Result<&BatchState, SimError>;
    /// The batch state, for loading a snapshot; call [`Backend::state_changed`] afterwards.
    fn state_mut(&mut self) -> Result<&mut BatchState, SimError>;
    /// Re-derive what depends on a state edited through [`Backend::state_mut`] for environment
    /// `env` (ORCA obstacles, observation) without stepping: `SimError::Shape` where its
    /// obstacles need more processed vertices than the config holds
    /// (`systems::orca_obstacles::rebuild_edited`; the environment's obstacles are then poisoned
    /// and its observation not rewritten).
    fn state_changed(&mut self, env: usize) -> Result<(), SimError>;
    /// Replace the step constants (same config; e.g. a new seed or replay mode).
    fn set_params(&mut self, params: StepParams);
    /// Host threads the backend works with, the caller included.
    fn threads(&self) -> usize;
    /// Time each stage of the following steps (off by default: it costs two clock reads per stage
    /// and chunk).
    fn set_stage_timing(&mut self, on: bool);
    /// Seconds spent in each stage while timing was on (order of `STAGES`).
    fn stage_seconds(&self) -> Vec<f64>;
    /// How the stages are timed, for reports: CPU time per chunk, GPU timestamps around each
    /// stage run alone, or the wall time of a submit per stage.
    fn stage_clock(&self) -> &'static str {
        "CPU time of each stage per chunk, summed over threads"
    }
    /// Short name, e.g. "cpu".
    fn name(&self) -> &'static str;
    /// How many GPU pipelines creating this batch compiled (0 when its device had compiled them
    /// for an earlier batch, and always 0 on the CPU).
    fn pipelines_compiled(&self) -> usize {
        0
    }
    /// What runs the batch, for logs and benchmark records: the CPU threads, or the GPU adapter.
    fn device(&self) -> String;
    /// Deliver only the optional per-step columns `which` selects from the next step on (see
    /// [`crate::outputs::StepOutputs`]): the GPU backend reads the others back no more; the CPU
    /// backend, which writes its outputs in place, keeps writing every column.
    fn set_step_outputs(&mut self, _which: crate::outputs::StepOutputs) {}
    /// The host path's totals (`None` on the CPU backend, which has none).
    fn host_path(&self) -> Option<HostPath> {
        None
    }
    /// Time the following steps' passes and readback on the device's clock (`HostPath`'s
    /// `device_s` and `readback_s`), where the device has timestamps; off by default.
    fn set_step_timeline(&mut self, _on: bool) {}
    /// Seconds `steps` steps take on the device alone (see `BatchEnv::time_device_steps`);
    /// `None` without a device.
    fn time_device_steps(
        &mut self,
        _actions: &[f32],
        _steps: usize,
    ) -> Result<Option<f64>, SimError> {
        Ok(None)
    }
}
