//! [`BatchEnv`]: the public face of the simulator. It validates what callers hand in (actions,
//! masks, state documents) with exact messages, then passes plain slices to the backend.

use std::panic::{AssertUnwindSafe, catch_unwind};

use crate::backend::cpu::panic_message;
use crate::backend::{Backend, BackendChoice};
use crate::config::{Config, Kinematics, RewardKind};
use crate::document;
use crate::error::SimError;
use crate::outputs::{Outputs, StepOutputs};
use crate::params::{AutoresetMode, StepParams};
use crate::pipeline::STAGES;
use crate::sngnn::SngnnReward;
use crate::spec::{DISCRETE_ACTIONS, ObsLayout};
use crate::state::{BatchState, Caps};

/// The most CPU threads a batch takes ([`EnvOptions::threads`]): more than the largest hosts'
/// cores, and few enough that a mistyped count is refused at once instead of starting hundreds
/// of thousands of threads.
pub const MAX_THREADS: usize = 1024;

/// Options of a batch that are not part of the scenario configuration.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EnvOptions {
    /// Number of environments.
    pub n_envs: usize,
    /// Seed of the batch: environment i's first episode has the episode seed `seed + i`
    /// (docs/spec.md, determinism); with the same config, seed and actions, every run is identical.
    pub seed: u64,
    /// What happens to finished environments.
    pub autoreset: AutoresetMode,
    /// CPU threads (all cores when `None`), 1 to [`MAX_THREADS`]; the GPU backend generates
    /// resets on them.
    pub threads: Option<usize>,
    /// Which backend steps the batch.
    pub backend: BackendChoice,
}

impl Default for EnvOptions {
    fn default() -> Self {
        Self {
            n_envs: 1,
            seed: 0,
            autoreset: AutoresetMode::NextStep,
            threads: None,
            backend: BackendChoice::Cpu,
        }
    }
}

/// Actions for every environment of the batch.
#[derive(Debug, Clone, Copy)]
pub enum Actions<'a> {
    /// 3 floats per environment in [-1, 1]: forward, lateral (0 for diff-drive), rotation;
    /// values outside are clipped after scaling, as 0.1.1 does.
    Continuous(&'a [f32]),
    /// One of the 7 discrete actions per environment ([`DISCRETE_ACTIONS`]).
    Discrete(&'a [u32]),
}

/// A batch of SocNavGym environments.
pub struct BatchEnv {
    config: Config,
    params: StepParams,
    caps: Caps,
    layout: ObsLayout,
    backend: Box<dyn Backend>,
    actions: Vec<f32>,
    step_outputs: StepOutputs,
}

impl std::fmt::Debug for BatchEnv {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BatchEnv")
            .field("n_envs", &self.n_envs())
            .field("backend", &self.backend.name())
            .field("caps", &self.caps)
            .finish()
    }
}

impl BatchEnv {
    /// One environment of `config` on the CPU with one thread, reset with `seed`, that never
    /// resets itself (`AutoresetMode::Disabled`): what a viewer, a renderer or a heatmap scene
    /// steps episode by episode.
    ///
    /// # Errors
    /// As [`BatchEnv::new`] and [`BatchEnv::reset`].
    pub fn single(config: Config, seed: u64) -> Result<Self, SimError> {
        let options = EnvOptions {
            n_envs: 1,
            seed,
            autoreset: AutoresetMode::Disabled,
            threads: Some(1),
            ..Default::default()
        };
        let mut env = Self::new(config, options)?;
        env.reset(Some(seed))?;
        Ok(env)
    }

    /// A batch of `options.n_envs` environments of `config` on the backend `options.backend`. Call
    /// [`BatchEnv::reset`] before the first step.
    pub fn new(config: Config, options: EnvOptions) -> Result<Self, SimError> {
        let choice = options.backend;
        Self::build(config, options, |params, state, out, threads, sngnn| {
            crate::backend::open(choice, params, state, out, threads, sngnn)
        })
    }

    /// A batch as [`BatchEnv::new`] makes it, on the GPU backend over `device` (`options.backend`
    /// is not consulted): a device of the caller's choosing, e.g. one of its own
    /// ([`GpuDevice::open_private`](crate::backend::gpu::GpuDevice::open_private)) whose loss
    /// touches no other batch.
    #[cfg(feature = "gpu")]
    pub fn on_device(
        config: Config,
        options: EnvOptions,
        device: crate::backend::gpu::GpuDevice,
    ) -> Result<Self, SimError> {
        Self::build(config, options, |params, state, out, threads, sngnn| {
            let gpu = crate::backend::gpu::GpuBackend::new(
                device,
                params,
                state,
                out,
                threads,
                sngnn.as_ref(),
            )?;
            Ok(Box::new(gpu))
        })
    }

    /// Validate `config` and `options`, then make the batch on the backend `open` returns.
    fn build(
        config: Config,
        options: EnvOptions,
        open: impl FnOnce(
            StepParams,
            BatchState,
            Outputs,
            Option<usize>,
            Option<SngnnReward>,
        ) -> Result<Box<dyn Backend>, SimError>,
    ) -> Result<Self, SimError> {
        let problems = crate::config::validate(&config);
        if !problems.is_empty() {
            return Err(SimError::config(problems));
        }
        if options.n_envs == 0 {
            return Err(SimError::shape(
                "n_envs",
                "a batch needs at least one environment, got n_envs = 0",
            ));
        }
        if let Some(n) = options.threads.filter(|n| !(1..=MAX_THREADS).contains(n)) {
            return Err(SimError::shape(
                "threads",
                format!("`threads` must be in 1..={MAX_THREADS}, got {n}"),
            ));
        }
        let caps = Caps::from_config(&config);
        let layout = ObsLayout::new(&caps, &config.observation);
        let params = StepParams::new(&config, options.autoreset);
        check_memory(options.n_envs, caps, layout)?;
        let state = BatchState::seeded(options.n_envs, caps, options.seed);
        let out = Outputs::new(options.n_envs, layout);
        let sngnn = match config.reward.kind {
            RewardKind::Sngnn => Some(SngnnReward::for_config(&config)?),
            RewardKind::Dsrnn => None,
        };
        let backend = open(params, state, out, options.threads, sngnn)?;
        let actions = vec![0.0; 3 * options.n_envs];
        Ok(Self {
            config,
            params,
            caps,
            layout,
            backend,
            actions,
            step_outputs: StepOutputs::ALL,
        })
    }

    /// Number of environments.
    pub fn n_envs(&self) -> usize {
        self.actions.len() / 3
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The step constants.
    pub fn params(&self) -> &StepParams {
        &self.params
    }

    /// Slot capacities per entity kind.
    pub fn caps(&self) -> &Caps {
        &self.caps
    }

    /// Observation layout of one environment.
    pub fn layout(&self) -> &ObsLayout {
        &self.layout
    }

    /// Name of the backend running the batch.
    pub fn backend_name(&self) -> &'static str {
        self.backend.name()
    }

    /// What runs the batch: the CPU threads, or the GPU adapter.
    pub fn device(&self) -> String {
        self.backend.device()
    }

    /// CPU threads in use.
    pub fn threads(&self) -> usize {
        self.backend.threads()
    }

    /// Reset every environment. With `Some(seed)`, environment i plays the episode of seed
    /// `seed + i` (wrapping; gymnasium's convention for vector environments), else each plays the
    /// next episode of its seed sequence (`seeds::next_episode_seed`).
    pub fn reset(&mut self, seed: Option<u64>) -> Result<(), SimError> {
        if let Some(seed) = seed {
            let seeds: Vec<Option<u64>> = (0..self.n_envs())
                .map(|e| Some(seed.wrapping_add(e as u64)))
                .collect();
            self.set_next_seeds(&seeds)?;
        }
        self.backend.reset(None)
    }

    /// Name the episode each environment plays at its next reset: entry i, when `Some(seed)`,
    /// gives environment i's next episode that seed (and restarts its episode count); `None`
    /// leaves its sequence alone. The episode of seed e is the same in any batch, at any index,
    /// on any backend, so a single environment reset with seed e replays it.
    ///
    /// # Errors
    /// `SimError::Shape` unless there is one entry per environment.
    pub fn set_next_seeds(&mut self, seeds: &[Option<u64>]) -> Result<(), SimError> {
        if seeds.len() != self.n_envs() {
            return Err(SimError::shape(
                "seeds",
                format!(
                    "{} seeds given for {} environments (one per environment, None to keep its sequence)",
                    seeds.len(),
                    self.n_envs()
                ),
            ));
        }
        if seeds.iter().all(Option::is_none) {
            return Ok(());
        }
        let state = self.backend.state_mut()?;
        for (e, seed) in seeds.iter().enumerate() {
            if let Some(seed) = *seed {
                state.set_next_seed(e, seed);
            }
        }
        Ok(())
    }

    /// Reset the environments whose mask entry is true (the DISABLED autoreset mode's reset).
    pub fn reset_envs(&mut self, mask: &[bool]) -> Result<(), SimError> {
        if mask.len() != self.n_envs() {
            return Err(SimError::shape(
                "reset mask",
                format!(
                    "reset mask has {} entries, expected one per environment ({})",
                    mask.len(),
                    self.n_envs()
                ),
            ));
        }
        self.backend.reset(Some(mask))
    }

    /// Step every environment. Invalid actions are rejected before anything moves.
    pub fn step(&mut self, actions: Actions<'_>) -> Result<(), SimError> {
        self.load_actions(actions)?;
        self.backend.step(&self.actions)
    }

    /// Seconds that `steps` steps with `actions` take on the device alone, or `None` on a
    /// backend without one (the CPU's). For benchmarks of the simulation on a GPU: the stages
    /// run back to back, no output reaches the host and no reset row is refilled, so an
    /// environment that ends twice within the window replays its row. The batch stays usable,
    /// but its trajectory is no longer the one `step` would have given.
    ///
    /// # Errors
    /// As [`BatchEnv::step`] for bad actions; `Device` if the device fails.
    pub fn time_device_steps(
        &mut self,
        actions: Actions<'_>,
        steps: usize,
    ) -> Result<Option<f64>, SimError> {
        self.load_actions(actions)?;
        self.backend.time_device_steps(&self.actions, steps)
    }

    /// Validate `actions` into the batch's action buffer (3 floats per environment).
    fn load_actions(&mut self, actions: Actions<'_>) -> Result<(), SimError> {
        self.check_actions(actions)?;
        match actions {
            Actions::Continuous(a) => self.actions.copy_from_slice(a),
            Actions::Discrete(a) => {
                for (chunk, &k) in self.actions.chunks_exact_mut(3).zip(a) {
                    chunk.copy_from_slice(&DISCRETE_ACTIONS[k as usize]);
                }
            }
        }
        Ok(())
    }

    /// The error [`BatchEnv::step`] would give for `actions`, if any, without stepping: for a
    /// caller that hands the step to another thread and wants a bad action refused at once.
    pub fn check_actions(&self, actions: Actions<'_>) -> Result<(), SimError> {
        let n = self.n_envs();
        match actions {
            Actions::Continuous(a) => {
                if a.len() != 3 * n {
                    return Err(SimError::action(
                        None,
                        format!(
                            "expected {} floats (3 per environment for {n} environments), got {}",
                            3 * n,
                            a.len()
                        ),
                    ));
                }
                if let Some(i) = a.iter().position(|v| !v.is_finite()) {
                    return Err(SimError::action(
                        Some(i / 3),
                        format!(
                            "environment {}: component {} is {} (actions must be finite)",
                            i / 3,
                            i % 3,
                            a[i]
                        ),
                    ));
                }
                if self.config.robot.kinematics == Kinematics::DiffDrive {
                    if let Some(e) = (0..n).find(|e| a[3 * e + 1] != 0.0) {
                        return Err(SimError::action(
                            Some(e),
                            format!(
                                "environment {e}: lateral component {} must be 0 for a diff-drive robot",
                                a[3 * e + 1]
                            ),
                        ));
                    }
                }
            }
            Actions::Discrete(a) => {
                if a.len() != n {
                    return Err(SimError::action(
                        None,
                        format!(
                            "expected {n} discrete actions (one per environment), got {}",
                            a.len()
                        ),
                    ));
                }
                if let Some(e) = a.iter().position(|&k| k as usize >= DISCRETE_ACTIONS.len()) {
                    return Err(SimError::action(
                        Some(e),
                        format!(
                            "environment {e}: discrete action {} is not in 0..{}",
                            a[e],
                            DISCRETE_ACTIONS.len()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The outputs of the last step or reset (overwritten by the next one).
    pub fn outputs(&self) -> &Outputs {
        self.backend.outputs()
    }

    /// Deliver only the optional per-step output columns `which` selects, from the next step
    /// or reset on (every column by default). A learner that reads the observation, reward and
    /// flags alone takes [`StepOutputs::LEAN`]: the GPU backend then reads a third fewer bytes
    /// back for exp2 with padded observations. A column left out is not kept current (see
    /// [`StepOutputs`]).
    pub fn set_step_outputs(&mut self, which: StepOutputs) {
        self.step_outputs = which;
        self.backend.set_step_outputs(which);
    }

    /// The optional per-step output columns delivered ([`BatchEnv::set_step_outputs`]).
    pub fn step_outputs(&self) -> StepOutputs {
        self.step_outputs
    }

    /// The batch state (read-only).
    ///
    /// # Errors
    /// `SimError::Device` when the GPU backend cannot download it (a lost device); never on the
    /// CPU backend.
    pub fn state(&self) -> Result<&BatchState, SimError> {
        self.backend.state()
    }

    /// How many GPU pipelines creating this batch compiled: 0 when an earlier batch in this
    /// process compiled them on the same device (pipelines depend on the config's size classes,
    /// never on the batch size), and always 0 on the CPU.
    pub fn pipelines_compiled(&self) -> usize {
        self.backend.pipelines_compiled()
    }

    /// The GPU backend's host path so far: bytes read back, finished rows, and the seconds spent
    /// refilling the reset pool, waiting for the device and copying its outputs (`None` on the
    /// CPU backend).
    pub fn host_path(&self) -> Option<crate::backend::HostPath> {
        self.backend.host_path()
    }

    /// Time the following steps' passes and readback copies on the device's clock, where the
    /// device has timestamp queries (`HostPath::device_s` and `readback_s` in
    /// [`BatchEnv::host_path`]); off by default, and nothing on the CPU backend.
    pub fn set_step_timeline(&mut self, on: bool) {
        self.backend.set_step_timeline(on);
    }

    /// Time each stage of the following steps ([`BatchEnv::stage_seconds`]); off by default.
    pub fn set_stage_timing(&mut self, on: bool) {
        self.backend.set_stage_timing(on);
    }

    /// How [`BatchEnv::stage_seconds`] is measured on this backend (for reports).
    pub fn stage_clock(&self) -> &'static str {
        self.backend.stage_clock()
    }

    /// Seconds spent per stage while stage timing was on, with the stage names.
    pub fn stage_seconds(&self) -> Vec<(&'static str, f64)> {
        STAGES
            .iter()
            .map(|s| s.name)
            .zip(self.backend.stage_seconds())
            .collect()
    }

    /// Replay mode: the random social events are not drawn (the golden replay re-synchronises
    /// the state with the reference instead).
    pub fn set_replay(&mut self, replay: bool) {
        self.params.replay = u32::from(replay);
        self.backend.set_params(self.params);
    }

    /// Environment `env` as a self-contained JSON document (docs/spec.md, fidelity).
    pub fn get_state(&self, env: usize) -> Result<serde_json::Value, SimError> {
        self.check_env(env)?;
        Ok(document::export(&self.params, self.backend.state()?, env))
    }

    /// Load environment `env` from a JSON document as [`BatchEnv::get_state`] writes it (or a
    /// golden episode's header and snapshot); its observation is rewritten from the loaded state.
    /// A rejected document leaves the environment as it was.
    pub fn set_state(&mut self, env: usize, doc: &serde_json::Value) -> Result<(), SimError> {
        self.check_env(env)?;
        // A document can fail half-way through (a missing key, a capacity), and so can what
        // follows from it (obstacles too many for the config's capacity): keep a copy to
        // restore, so that a failed load changes nothing. A panic on the way (a bug: a document
        // the checks let through that breaks an invariant) is caught and restored the same way.
        let mut backup = BatchState::new(1, self.caps);
        backup.copy_env_from(0, self.backend.state_mut()?, env);
        let params = self.params;
        // Whether the load reached what follows from the state (and may have written to it).
        let mut derived = false;
        let loaded = catch_unwind(AssertUnwindSafe(|| {
            document::import(&params, self.backend.state_mut()?, env, doc)?;
            derived = true;
            self.backend.state_changed(env).map_err(|err| match err {
                SimError::Shape { message, .. } => SimError::shape("state document", message),
                other => other,
            })
        }))
        .unwrap_or_else(|payload| Err(SimError::Internal(panic_message(payload.as_ref()))));
        if loaded.is_err() {
            self.backend.state_mut()?.copy_env_from(env, &backup, 0);
            if derived {
                self.backend.state_changed(env)?;
            }
        }
        loaded
    }

    /// Replace the whole batch state with `other`'s (a batch of the same config and size,
    /// possibly on another backend): both then step from identical states. The outputs are
    /// left as they are until the next step or reset.
    ///
    /// # Errors
    /// `SimError::Shape` when the batches differ in size or capacities.
    pub fn copy_state_from(&mut self, other: &BatchEnv) -> Result<(), SimError> {
        // The state's derived columns (the processed obstacles, say) follow from the config's
        // constants, which the step takes from the batch: another config's would not be its.
        if other.params != self.params {
            return Err(SimError::shape(
                "state",
                "cannot copy the state of a batch of another config (its step constants differ)",
            ));
        }
        if other.n_envs() != self.n_envs() || other.caps != self.caps {
            return Err(SimError::shape(
                "state",
                format!(
                    "cannot copy the state of a batch of {} environments with capacities {:?} into one of {} with {:?}",
                    other.n_envs(),
                    other.caps,
                    self.n_envs(),
                    self.caps
                ),
            ));
        }
        self.backend.state_mut()?.clone_from(other.state()?);
        Ok(())
    }

    fn check_env(&self, env: usize) -> Result<(), SimError> {
        if env >= self.n_envs() {
            return Err(SimError::EnvIndex {
                env,
                n_envs: self.n_envs(),
            });
        }
        Ok(())
    }
}

/// Refuse a batch the host cannot hold before allocating it (an allocation failure aborts the
/// process, the Python interpreter with it): the state and outputs of `n_envs` environments,
/// twice over for the backends' copies (the reset pool, the GPU's host mirror), must be
/// reservable. Linux grants reservations up to about its memory and swap, so this catches a
/// batch far too large; one that fits the reservation but not the memory in use is the
/// operating system's to refuse.
fn check_memory(n_envs: usize, caps: Caps, layout: ObsLayout) -> Result<(), SimError> {
    let per_env = 4
        * (BatchState::new(1, caps)
            .columns()
            .iter()
            .map(|c| c.2)
            .sum::<usize>()
            + Outputs::new(1, layout)
                .columns()
                .iter()
                .map(|c| c.2)
                .sum::<usize>()
            + 3);
    let bytes = n_envs.checked_mul(2).and_then(|n| n.checked_mul(per_env));
    let reservable = bytes.is_some_and(|b| Vec::<u8>::new().try_reserve_exact(b).is_ok());
    if reservable {
        return Ok(());
    }
    let bytes = (per_env as u64).saturating_mul((n_envs as u64).saturating_mul(2));
    Err(SimError::OutOfMemory {
        bytes,
        device: None,
        message: format!(
            "a batch of {n_envs} environments needs about {:.1} GB ({per_env} bytes of state and \
             outputs per environment, twice over), more than this machine can reserve: use fewer \
             environments",
            bytes as f64 / 1e9
        ),
    })
}
