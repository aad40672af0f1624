//! [`GpuBackend`]: the whole step on the device, one submit per step.
//!
//! Per step the host uploads the actions, records one compute pass with the dispatches of the
//! stages of [`STAGES`] in order (one per stage, or one for consecutive members of a fused pass,
//! `pipeline::FusedPass`; wgpu orders the dispatches through their storage-buffer barriers), copies the
//! outputs and the episode counters into a mapped readback buffer in the same submit, and reads
//! them into the host outputs it keeps ([`Backend::outputs`]) without allocating.
//!
//! With the SNGNN-v2 reward, the step includes the stages only that reward runs: `sngnn_graph`
//! (frames and packed graphs of the environments the reward scores) and `sngnn_score` (the
//! network's dispatches, [`super::GpuNet`]), still in the same pass and submit; the network's
//! status words are read back with the outputs.
//!
//! Resets copy rows of the reset pool (`src/backend/reset_pool.rs`), two per environment (its
//! next episode's and the one after, `backend::gpu::pool_rows`): an environment whose episode
//! counter moved on the device has consumed its next row (and its next episode seed moved one
//! step along the sequence, which the host follows without reading it back), so its other row
//! becomes the next, and the host generates the one two episodes ahead (on its worker threads,
//! for all such environments at once) while the device runs the following step.
//!
//! The state stays on the device; [`Backend::state`] downloads a host copy when asked and keeps
//! it until the next step, and [`Backend::state_mut`] edits that copy, which is uploaded before
//! the next device work.

use std::sync::{Arc, OnceLock};
use std::time::Instant;

use crate::backend::Backend;
use crate::backend::reset_pool;
use crate::error::SimError;
use crate::outputs::Outputs;
use crate::params::StepParams;
use crate::pipeline::STAGES;
use crate::sngnn::SngnnReward;
use crate::state::{BatchState, Caps};

use super::pool_rows::{PoolRows, Which};
use super::{GpuDevice, GpuStages, StepRead};

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
    /// Which episode each row of the reset pool starts ([`PoolRows`]).
    rows: PoolRows,
    /// Episode counters read back by the last device work.
    read_episode: Vec<u32>,
    scratches: reset_pool::Scratches,
    threads: usize,
    /// The host's threads: the reset pool's rows, the copies into the outputs and into wgpu's
    /// staging memory (`GpuStages::set_host_threads`).
    pool: Option<Arc<rayon::ThreadPool>>,
    timing: bool,
    stage_seconds: Vec<f64>,
    actions_mask: Vec<f32>,
    /// The stages of a step ([`step_stages`]).
    step_stages: Vec<&'static str>,
    /// Seconds spent refilling the reset pool before submitting, and while the device worked.
    refill_s: f64,
    refill_ahead_s: f64,
    /// Rows generated while the device worked.
    ahead_rows: u64,
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
        let step_stages = step_stages(sngnn.is_some());
        let mut stages = step_stages.clone();
        stages.push(crate::backend::schedule::RESET_PASS);
        let mut gpu = match sngnn {
            None => GpuStages::new(dev, &params, &state, &out, &stages)?,
            Some(r) => {
                let mut gpu =
                    GpuStages::with_sngnn_graphs(dev, &params, &state, &out, &stages, r.graphs)?;
                gpu.attach_sngnn_net(r.scorer.model(), r.scorer.tables())?;
                gpu
            }
        };
        let threads = crate::backend::cpu::resolve_threads(threads);
        // The caller waits while the rows are generated: every thread is a worker.
        let pool = crate::backend::cpu::thread_pool(threads, "socnav-reset")?.map(Arc::new);
        gpu.set_host_threads(pool.clone());
        let n = state.n_envs;
        let caps = state.strides;
        let layout = out.strides.layout;
        let episode = state.episode.clone();
        let row_words = gpu.pool_row_words();
        let scratches =
            reset_pool::Scratches::new(caps, layout, gpu.pool_obstacles(), pool.as_deref());
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
            rows: PoolRows::new(n, row_words),
            read_episode: vec![0; n],
            scratches,
            threads,
            pool,
            timing: false,
            stage_seconds: vec![0.0; STAGES.len()],
            actions_mask: vec![0.0; 3 * n],
            step_stages,
            refill_s: 0.0,
            refill_ahead_s: 0.0,
            ahead_rows: 0,
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
        let start = Instant::now();
        let refilled = self.refill();
        self.refill_s += start.elapsed().as_secs_f64();
        refilled
    }

    /// Generate the next rows the pool lacks (after an edit of the state, new seeds or new
    /// constants: normally none) and write them to the device.
    fn refill(&mut self) -> Result<(), SimError> {
        self.rows
            .select(Which::Next, &self.episode, &self.next_seed);
        self.rows
            .generate(&self.params, self.pool.as_deref(), &self.scratches);
        self.rows.write(&mut self.gpu);
        Ok(())
    }

    /// Run the step's stages, or the reset pass alone (one submit, or one per stage and timed),
    /// read the outputs and episode counters back, and account for the pool rows consumed.
    fn run(&mut self, step: bool) -> Result<(), SimError> {
        let _ = self.state.take();
        let stages: &[&'static str] = if step {
            &self.step_stages
        } else {
            &[crate::backend::schedule::RESET_PASS]
        };
        let read = StepRead {
            out: &mut self.out,
            episode: &mut self.read_episode,
            pool: self.pool.as_deref(),
        };
        // While the device works: the rows two episodes ahead that the pool lacks, generated and
        // staged for the next submit (they go to the half of the pool this step does not read).
        let (rows, params, pool, scratches) = (
            &mut self.rows,
            &self.params,
            self.pool.as_deref(),
            &self.scratches,
        );
        let (episode, next_seed) = (&self.episode, &self.next_seed);
        let (mut ahead_s, mut ahead_rows) = (0.0, 0);
        let ahead = |gpu: &mut GpuStages| {
            let start = Instant::now();
            rows.select(Which::Ahead, episode, next_seed);
            ahead_rows = rows.selected() as u64;
            rows.generate(params, pool, scratches);
            rows.write(gpu);
            ahead_s = start.elapsed().as_secs_f64();
        };
        if self.timing && step {
            if let Some(times) = self.gpu.time_passes(stages)? {
                for (stage, t) in stages.iter().zip(times) {
                    self.stage_seconds[stage_of(stage)] += t;
                }
            } else {
                for stage in stages {
                    let start = Instant::now();
                    self.gpu.run(stage)?;
                    self.gpu.wait()?;
                    self.stage_seconds[stage_of(stage)] += start.elapsed().as_secs_f64();
                }
            }
            self.gpu.run_stages(&[], Some(read), ahead)?;
        } else {
            self.gpu.run_stages(stages, Some(read), ahead)?;
        }
        self.refill_ahead_s += ahead_s;
        self.ahead_rows += ahead_rows;
        let mut error = None;
        for e in 0..self.episode.len() {
            if self.read_episode[e] != self.episode[e] {
                let (seed, failed) = self.rows.consumed(e, self.episode[e]);
                if let Some(err) = failed {
                    error.get_or_insert(err);
                }
                self.episode[e] = self.read_episode[e];
                // The row set the next seed one step along (scenario::reset_env).
                self.next_seed[e] = crate::seeds::next_episode_seed(seed);
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

/// The stages of a step: those of `STAGES`, in order, those only the SNGNN-v2 reward runs
/// included when it is the reward (`GpuStages` plans their dispatches).
pub(super) fn step_stages(sngnn: bool) -> Vec<&'static str> {
    STAGES
        .iter()
        .filter(|s| sngnn || !s.sngnn_reward_only)
        .map(|s| s.name)
        .collect()
}

/// The index in `STAGES` of a stage of the step, for its time.
#[expect(
    clippy::expect_used,
    reason = "the stages are taken from STAGES (step_stages)"
)]
fn stage_of(stage: &str) -> usize {
    STAGES
        .iter()
        .position(|s| s.name == stage)
        .expect("every stage of the step is in STAGES")
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

    fn set_step_timeline(&mut self, on: bool) {
        self.gpu.set_step_timeline(on);
    }

    fn set_step_outputs(&mut self, which: crate::outputs::StepOutputs) {
        self.gpu.set_step_outputs(which);
    }

    fn host_path(&self) -> Option<crate::backend::HostPath> {
        let mut path = self.gpu.host_path();
        path.refill_s = self.refill_s;
        path.refill_ahead_s = self.refill_ahead_s;
        path.ahead_rows = self.ahead_rows;
        Some(path)
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
            self.gpu.run_stages(&self.step_stages, None, |_| {})?;
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
        // Edited, whether or not the rebuild fits: a failed one leaves poisoned columns.
        self.state_edited = true;
        let mut s = downloaded(&mut self.state)?.env_chunk(env);
        crate::systems::orca_obstacles::rebuild_edited(&p, &mut s, 0, env)?;
        let mut o = self.out.env_chunk(env);
        crate::systems::observation::write_observation(&p, &mut s, &mut o, 0);
        self.outputs_edited = true;
        Ok(())
    }

    fn set_params(&mut self, params: StepParams) {
        self.params = params;
        self.gpu.upload_params(&params);
        // Every row depends on the constants.
        self.rows.invalidate();
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

    fn stage_clock(&self) -> &'static str {
        if self.gpu.has_timestamps() {
            "GPU timestamps around each stage run alone, all in one submit"
        } else {
            "wall time of a submit and wait per stage"
        }
    }

    fn name(&self) -> &'static str {
        "gpu"
    }

    fn device(&self) -> String {
        self.gpu.device_description()
    }
}
