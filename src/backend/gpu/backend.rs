//! [`GpuBackend`]: the whole step on the device, one submit per step.
//!
//! Per step the host uploads the actions, records one compute pass with one dispatch per stage of
//! [`STAGES`] (wgpu orders the dispatches through their storage-buffer barriers), copies the
//! outputs and the episode counters into a mapped readback buffer in the same submit, and reads
//! them into the host outputs it keeps ([`Backend::outputs`]) without allocating.
//!
//! With the SNGNN-v2 reward, the step includes the stages only that reward runs: `sngnn_graph`
//! (frames and packed graphs of the environments the reward scores) and `sngnn_score` (the
//! network's dispatches, [`super::GpuNet`]), still in the same pass and submit; the network's
//! status words are read back with the outputs.
//!
//! Resets copy rows of the reset pool (`src/backend/reset_pool.rs`): an environment whose episode
//! counter moved on the device has consumed its row (and its next episode seed moved one step
//! along the sequence, which the host follows without reading it back), and the host generates
//! its next one (on its worker threads, for all such environments at once) before the next
//! device work. The state stays on the device; [`Backend::state`] downloads a host copy when
//! asked and keeps it until the next step, and [`Backend::state_mut`] edits that copy, which is
//! uploaded before the next device work.

use std::sync::OnceLock;
use std::time::Instant;

use crate::backend::Backend;
use crate::backend::reset_pool;
use crate::error::SimError;
use crate::outputs::Outputs;
use crate::params::StepParams;
use crate::pipeline::STAGES;
use crate::sngnn::SngnnReward;
use crate::state::{BatchState, Caps};

use super::{GpuDevice, GpuStages};

/// `row_episode` of a pool row that holds nothing valid.
const NO_ROW: u32 = u32::MAX;

/// The GPU backend.
pub struct GpuBackend {
    params: StepParams,
    gpu: GpuStages,
    caps: Caps,
    out: Outputs,
    /// The host copy of the device state, when one was asked for since the last device work.
    state: OnceLock<BatchState>,
    /// The host copy of the state was edited: upload it before the next device work.
    state_edited: bool,
    /// The host outputs were edited: upload them before the next device work.
    outputs_edited: bool,
    /// Each environment's episode counter on the device, as last read back.
    episode: Vec<u32>,
    /// Each environment's next episode seed on the device.
    next_seed: Vec<u64>,
    /// The episode counter each pool row was generated for ([`NO_ROW`]: none).
    row_episode: Vec<u32>,
    /// The episode seed each pool row was generated for.
    row_seed: Vec<u64>,
    /// Rows whose scenario could not be generated: the error, raised when the row is consumed
    /// (the step at which the CPU backend's reset would fail).
    row_errors: Vec<Option<SimError>>,
    /// Episode counters read back by the last device work.
    read_episode: Vec<u32>,
    /// Reused buffers of the pool refill.
    stale: Vec<usize>,
    rows: Vec<u32>,
    scratches: reset_pool::Scratches,
    threads: usize,
    pool: Option<rayon::ThreadPool>,
    timing: bool,
    stage_seconds: Vec<f64>,
    actions_mask: Vec<f32>,
    /// The passes of a step ([`step_passes`]).
    step_passes: Vec<&'static str>,
}

impl std::fmt::Debug for GpuBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuBackend")
            .field("adapter", &self.gpu.adapter().name)
            .field("n_envs", &self.episode.len())
            .finish_non_exhaustive()
    }
}

impl GpuBackend {
    /// A backend over `state` and `out` on `dev`; `threads` host threads generate the reset rows
    /// (all cores when `None`); `sngnn` scores the steps when the reward is SNGNN-v2's.
    ///
    /// # Errors
    /// `OutOfMemory` when the batch does not fit the adapter's memory or bindings;
    /// `BackendUnavailable` when a stage has no shader, a shader fails to build, or the SNGNN-v2
    /// reward cannot run on the device (see `GpuStages::with_sngnn_graphs`: episodes too long for
    /// its frame-gap table).
    pub fn new(
        dev: GpuDevice,
        params: StepParams,
        state: BatchState,
        out: Outputs,
        threads: Option<usize>,
        sngnn: Option<&SngnnReward>,
    ) -> Result<Self, SimError> {
        let step_passes = step_passes(sngnn.is_some());
        let mut passes = step_passes.clone();
        passes.push(crate::backend::wgsl::RESET_PASS);
        let gpu = match sngnn {
            None => GpuStages::new(dev, &params, &state, &out, &passes)?,
            Some(r) => {
                let mut gpu =
                    GpuStages::with_sngnn_graphs(dev, &params, &state, &out, &passes, r.graphs)?;
                gpu.attach_sngnn_net(r.scorer.model(), r.scorer.tables())?;
                gpu
            }
        };
        let threads = crate::backend::cpu::resolve_threads(threads);
        // The caller waits while the rows are generated: every thread is a worker.
        let pool = crate::backend::cpu::thread_pool(threads, "socnav-reset")?;
        let n = state.n_envs;
        let caps = state.strides;
        let layout = out.strides.layout;
        let episode = state.episode.clone();
        let next_seed = (0..n).map(|e| state.next_seed(e)).collect();
        Ok(Self {
            params,
            gpu,
            caps,
            out,
            state: OnceLock::from(state),
            state_edited: false,
            outputs_edited: false,
            episode,
            next_seed,
            row_episode: vec![NO_ROW; n],
            row_seed: vec![0; n],
            row_errors: (0..n).map(|_| None).collect(),
            read_episode: vec![0; n],
            stale: Vec::new(),
            rows: Vec::new(),
            scratches: reset_pool::Scratches::new(caps, layout, pool.as_ref()),
            threads,
            pool,
            timing: false,
            stage_seconds: vec![0.0; STAGES.len()],
            actions_mask: vec![0.0; 3 * n],
            step_passes,
        })
    }

    /// The adapter the batch runs on.
    pub fn adapter(&self) -> &super::AdapterSummary {
        self.gpu.adapter()
    }

    /// Upload what the host edited and refill the pool rows that are stale (`SimError::Device`
    /// once the device is lost: the batch is then closed for good).
    fn prepare(&mut self) -> Result<(), SimError> {
        self.gpu.check_lost()?;
        if let Some(s) = self.state.get().filter(|_| self.state_edited) {
            self.gpu.upload_state(s);
            self.episode.copy_from_slice(&s.episode);
            for (e, seed) in self.next_seed.iter_mut().enumerate() {
                *seed = s.next_seed(e);
            }
            self.state_edited = false;
        }
        if self.outputs_edited {
            self.gpu.upload_outputs(&self.out);
            self.outputs_edited = false;
        }
        self.refill()
    }

    /// Generate the pool rows of the environments whose row is not for their current episode
    /// counter and next seed, and write them to the device (consecutive environments in one
    /// write).
    fn refill(&mut self) -> Result<(), SimError> {
        self.stale.clear();
        self.stale.extend((0..self.episode.len()).filter(|&e| {
            self.row_episode[e] != self.episode[e] || self.row_seed[e] != self.next_seed[e]
        }));
        if self.stale.is_empty() {
            return Ok(());
        }
        let words = self.gpu.pool_row_words();
        self.rows.clear();
        self.rows.resize(self.stale.len() * words, 0);
        let failed = reset_pool::write_rows(
            &self.params,
            &self.stale,
            &self.episode,
            &self.next_seed,
            &mut self.rows,
            self.pool.as_ref(),
            &self.scratches,
        );
        for &e in &self.stale {
            self.row_episode[e] = self.episode[e];
            self.row_seed[e] = self.next_seed[e];
            self.row_errors[e] = None;
        }
        for (e, err) in failed {
            self.row_errors[e] = Some(err);
        }
        let mut k = 0;
        while k < self.stale.len() {
            let mut end = k + 1;
            while end < self.stale.len() && self.stale[end] == self.stale[end - 1] + 1 {
                end += 1;
            }
            self.gpu
                .write_pool_rows(self.stale[k], &self.rows[k * words..end * words]);
            k = end;
        }
        Ok(())
    }

    /// Run the step's passes, or the reset pass alone (one submit, or one per pass and timed),
    /// read the outputs and episode counters back, and account for the pool rows consumed.
    fn run(&mut self, step: bool) -> Result<(), SimError> {
        let _ = self.state.take();
        let passes: &[&'static str] = if step {
            &self.step_passes
        } else {
            &[crate::backend::wgsl::RESET_PASS]
        };
        if self.timing && step {
            for pass in passes {
                let start = Instant::now();
                self.gpu.run(pass)?;
                self.gpu.wait()?;
                self.stage_seconds[stage_of(pass)] += start.elapsed().as_secs_f64();
            }
            self.gpu
                .run_stages(&[], Some((&mut self.out, &mut self.read_episode)))?;
        } else {
            self.gpu
                .run_stages(passes, Some((&mut self.out, &mut self.read_episode)))?;
        }
        let mut error = None;
        for e in 0..self.episode.len() {
            if self.read_episode[e] != self.episode[e] {
                if let Some(err) = self.row_errors[e].take() {
                    error.get_or_insert(err);
                }
                self.episode[e] = self.read_episode[e];
                // The row set the next seed one step along (scenario::reset_env).
                self.next_seed[e] = crate::seeds::next_episode_seed(self.row_seed[e]);
            }
        }
        if let Some(e) = self.gpu.sngnn_failure() {
            error.get_or_insert(e);
        }
        error.map_or(Ok(()), Err)
    }

    /// The host copy of the state, downloaded if there is none (`SimError::Device` when the
    /// download fails: a lost device).
    fn host_state(&self) -> Result<&BatchState, SimError> {
        // A copy read before the loss would be the state of a batch that can no longer step.
        self.gpu.check_lost()?;
        if let Some(s) = self.state.get() {
            return Ok(s);
        }
        let mut s = BatchState::new(self.episode.len(), self.caps);
        self.gpu.download_state(&mut s)?;
        Ok(self.state.get_or_init(|| s))
    }
}

/// The host state of `cell`, which [`GpuBackend::host_state`] has just filled.
fn downloaded(cell: &mut OnceLock<BatchState>) -> Result<&mut BatchState, SimError> {
    cell.get_mut()
        .ok_or_else(|| SimError::Internal("the host state was not downloaded first".into()))
}

/// The passes of a step: the stages of `STAGES`, in order, those only the SNGNN-v2 reward runs
/// included when it is the reward.
fn step_passes(sngnn: bool) -> Vec<&'static str> {
    STAGES
        .iter()
        .filter(|s| sngnn || !s.sngnn_reward_only)
        .map(|s| s.name)
        .collect()
}

/// The index in `STAGES` of a pass of the step, for its time.
#[expect(
    clippy::expect_used,
    reason = "the passes are taken from STAGES (step_passes)"
)]
fn stage_of(pass: &str) -> usize {
    STAGES
        .iter()
        .position(|s| s.name == pass)
        .expect("every pass of the step is a stage")
}

impl Backend for GpuBackend {
    fn reset(&mut self, mask: Option<&[bool]>) -> Result<(), SimError> {
        let n = self.episode.len();
        if let Some(m) = mask {
            if m.len() != n {
                return Err(SimError::shape(
                    "reset mask",
                    format!("reset mask has {} entries for {n} environments", m.len()),
                ));
            }
        }
        self.prepare()?;
        for e in 0..n {
            self.actions_mask[3 * e] = if mask.is_none_or(|m| m[e]) { 1.0 } else { 0.0 };
        }
        self.gpu.upload_actions(&self.actions_mask);
        self.run(false)
    }

    fn step(&mut self, actions: &[f32]) -> Result<(), SimError> {
        assert_eq!(
            actions.len(),
            3 * self.episode.len(),
            "actions are validated by BatchEnv::step"
        );
        self.prepare()?;
        self.gpu.upload_actions(actions);
        self.run(true)
    }

    fn time_device_steps(
        &mut self,
        actions: &[f32],
        steps: usize,
    ) -> Result<Option<f64>, SimError> {
        self.prepare()?;
        self.gpu.upload_actions(actions);
        let _ = self.state.take();
        self.gpu.wait()?;
        let start = Instant::now();
        for _ in 0..steps {
            self.gpu.run_stages(&self.step_passes, None)?;
        }
        self.gpu.wait()?;
        Ok(Some(start.elapsed().as_secs_f64()))
    }

    fn outputs(&self) -> &Outputs {
        &self.out
    }

    fn state(&self) -> Result<&BatchState, SimError> {
        self.host_state()
    }

    fn state_mut(&mut self) -> Result<&mut BatchState, SimError> {
        self.host_state()?;
        self.state_edited = true;
        downloaded(&mut self.state)
    }

    fn state_changed(&mut self, env: usize) -> Result<(), SimError> {
        let p = self.params;
        self.host_state()?;
        let mut s = downloaded(&mut self.state)?.env_chunk(env);
        crate::systems::orca_obstacles::rebuild_if_dirty(&p, &mut s, 0);
        let mut o = self.out.env_chunk(env);
        crate::systems::observation::write_observation(&p, &mut s, &mut o, 0);
        self.state_edited = true;
        self.outputs_edited = true;
        Ok(())
    }

    fn set_params(&mut self, params: StepParams) {
        self.params = params;
        self.gpu.upload_params(&params);
        // Every row depends on the constants.
        self.row_episode.fill(NO_ROW);
    }

    fn threads(&self) -> usize {
        self.threads
    }

    fn set_stage_timing(&mut self, on: bool) {
        self.timing = on;
    }

    fn stage_seconds(&self) -> Vec<f64> {
        self.stage_seconds.clone()
    }

    fn pipelines_compiled(&self) -> usize {
        self.gpu.pipelines_compiled()
    }

    fn name(&self) -> &'static str {
        "gpu"
    }

    fn device(&self) -> String {
        self.gpu.adapter().to_string()
    }
}
