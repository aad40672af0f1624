//! The CPU backend: the reference implementation. The batch is split recursively in halves
//! (`rayon::join`, no allocation) down to chunks of [`CHUNK_ENVS`] environments; each chunk runs
//! every stage of [`STAGES`] in order over its environments, so a chunk's state stays in cache
//! across stages. Environments never read each other, so results do not depend on the number of
//! threads or on the chunking.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use crate::error::SimError;
use crate::outputs::Outputs;
use crate::params::StepParams;
use crate::pipeline::{Batch, STAGES};
use crate::state::BatchState;

use super::Backend;

/// Environments per chunk: small enough to split the work evenly over the threads, large enough
/// that a chunk's per-stage timing costs nothing next to its work.
pub const CHUNK_ENVS: usize = 32;

/// The CPU backend.
#[derive(Debug)]
pub struct CpuBackend {
    params: StepParams,
    state: BatchState,
    out: Outputs,
    pool: rayon::ThreadPool,
    stage_nanos: Vec<AtomicU64>,
}

impl CpuBackend {
    /// A backend over `state` and `out` running on `threads` threads (all cores when `None`).
    pub fn new(
        params: StepParams,
        state: BatchState,
        out: Outputs,
        threads: Option<usize>,
    ) -> Result<Self, SimError> {
        let mut builder =
            rayon::ThreadPoolBuilder::new().thread_name(|i| format!("socnav-cpu-{i}"));
        if let Some(n) = threads {
            builder = builder.num_threads(n);
        }
        let pool = builder.build().map_err(|e| {
            SimError::BackendUnavailable(format!("cannot start the CPU thread pool: {e}"))
        })?;
        let stage_nanos = STAGES.iter().map(|_| AtomicU64::new(0)).collect();
        Ok(Self {
            params,
            state,
            out,
            pool,
            stage_nanos,
        })
    }

    /// The step constants.
    pub fn params(&self) -> &StepParams {
        &self.params
    }

    /// Replace the step constants (same config; e.g. a new seed or replay mode).
    pub fn set_params(&mut self, params: StepParams) {
        self.params = params;
    }

    /// Number of threads of the pool.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// Run `work` over every environment of the batch, in parallel chunks.
    fn run(
        &mut self,
        actions: &[f32],
        work: &(dyn Fn(&StepParams, &mut Batch<'_>, &[AtomicU64]) + Sync),
    ) -> Result<(), SimError> {
        let batch = Batch {
            s: self.state.chunk(),
            o: self.out.chunk(),
            actions,
            error: None,
        };
        let params = &self.params;
        let nanos = &self.stage_nanos;
        let err = self.pool.install(|| split(params, batch, nanos, work));
        err.map_or(Ok(()), Err)
    }
}

fn split(
    p: &StepParams,
    mut batch: Batch<'_>,
    nanos: &[AtomicU64],
    work: &(dyn Fn(&StepParams, &mut Batch<'_>, &[AtomicU64]) + Sync),
) -> Option<SimError> {
    if batch.n_envs() > CHUNK_ENVS {
        let mid = batch.n_envs() / 2;
        let (a, b) = batch.split_at(mid);
        let (ea, eb) = rayon::join(|| split(p, a, nanos, work), || split(p, b, nanos, work));
        ea.or(eb)
    } else {
        work(p, &mut batch, nanos);
        batch.error
    }
}

/// Every stage in order over the chunk's environments, timing each stage.
fn step_chunk(p: &StepParams, b: &mut Batch<'_>, nanos: &[AtomicU64]) {
    for (stage, counter) in STAGES.iter().zip(nanos) {
        let start = Instant::now();
        for e in 0..b.n_envs() {
            (stage.run)(p, b, e);
        }
        counter.fetch_add(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
    }
}

impl Backend for CpuBackend {
    fn reset(&mut self, mask: Option<&[bool]>) -> Result<(), SimError> {
        if let Some(m) = mask {
            if m.len() != self.state.n_envs {
                return Err(SimError::Shape(format!(
                    "reset mask has {} entries for {} environments",
                    m.len(),
                    self.state.n_envs
                )));
            }
        }
        self.run(&[], &|p, b, _| {
            for e in 0..b.n_envs() {
                let env = b.s.first_env + e;
                if mask.is_none_or(|m| m[env]) {
                    b.o.has_final[e] = 0;
                    b.o.episode_done[e] = 0;
                    crate::systems::reset::reset_and_observe(p, b, e);
                }
            }
        })
    }

    fn step(&mut self, actions: &[f32]) -> Result<(), SimError> {
        assert_eq!(
            actions.len(),
            3 * self.state.n_envs,
            "actions are validated by BatchEnv::step"
        );
        self.run(actions, &step_chunk)
    }

    fn outputs(&self) -> &Outputs {
        &self.out
    }

    fn state(&self) -> &BatchState {
        &self.state
    }

    fn state_mut(&mut self) -> &mut BatchState {
        &mut self.state
    }

    fn state_changed(&mut self, env: usize) {
        let p = self.params;
        let (_, rest) = self.state.chunk().split_at(env);
        let (mut s, _) = rest.split_at(1);
        crate::systems::orca_obstacles::rebuild_if_dirty(&p, &mut s, 0);
        let (_, orest) = self.out.chunk().split_at(env);
        let (mut o, _) = orest.split_at(1);
        crate::systems::observation::write_observation(&p, &mut s, &mut o, 0);
    }

    fn stage_seconds(&self) -> Vec<f64> {
        self.stage_nanos
            .iter()
            .map(|n| n.load(Ordering::Relaxed) as f64 * 1e-9)
            .collect()
    }

    fn name(&self) -> &'static str {
        "cpu"
    }
}
