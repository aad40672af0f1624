//! The CPU backend: the reference implementation. Each chunk of [`CHUNK_ENVS`] environments runs
//! every stage of [`STAGES`] in order over its environments, so a chunk's state stays in cache
//! across stages. Environments never read each other, so results do not depend on the number of
//! threads or on the chunking.
//!
//! Threads: the calling thread works too. It takes the first 1/T of the batch and hands the rest
//! to a pool of T − 1 workers (`rayon`, split recursively in halves with `join`, no allocation),
//! so no step waits for a parked caller to be woken up: on virtual machines that wake-up cost
//! up to a third of a 1 ms step.

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
    /// Threads in all, the caller included.
    threads: usize,
    /// The T − 1 workers beside the caller; none with one thread.
    pool: Option<rayon::ThreadPool>,
    stage_nanos: Vec<AtomicU64>,
    /// Whether steps time their stages.
    timing: bool,
}

impl CpuBackend {
    /// A backend over `state` and `out` running on `threads` threads (all cores when `None`).
    pub fn new(
        params: StepParams,
        state: BatchState,
        out: Outputs,
        threads: Option<usize>,
    ) -> Result<Self, SimError> {
        let threads =
            threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        let pool = if threads > 1 {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads - 1)
                .thread_name(|i| format!("socnav-cpu-{i}"))
                .build()
                .map_err(|e| {
                    SimError::BackendUnavailable(format!("cannot start the CPU thread pool: {e}"))
                })?;
            Some(pool)
        } else {
            None
        };
        let stage_nanos = STAGES.iter().map(|_| AtomicU64::new(0)).collect();
        Ok(Self {
            params,
            state,
            out,
            threads,
            pool,
            stage_nanos,
            timing: false,
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

    /// Threads stepping the batch, the caller included.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Run `work` over every environment of the batch: the caller's share on this thread, the
    /// rest on the pool.
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
        let nanos = &self.stage_nanos[..];
        let pool = match &self.pool {
            // One chunk is not worth a hand-over to another thread.
            Some(pool) if batch.n_envs() > CHUNK_ENVS => pool,
            _ => return sequential(params, batch, nanos, work).map_or(Ok(()), Err),
        };
        let share = batch.n_envs().div_ceil(self.threads);
        let (mine, rest) = batch.split_at(share);
        let mut rest_err = None;
        let mut mine_err = None;
        pool.in_place_scope(|scope| {
            scope.spawn(|_| rest_err = split(params, rest, nanos, work));
            mine_err = sequential(params, mine, nanos, work);
        });
        mine_err.or(rest_err).map_or(Ok(()), Err)
    }
}

/// `work` over the batch chunk by chunk on this thread.
fn sequential(
    p: &StepParams,
    mut batch: Batch<'_>,
    nanos: &[AtomicU64],
    work: &(dyn Fn(&StepParams, &mut Batch<'_>, &[AtomicU64]) + Sync),
) -> Option<SimError> {
    let mut first_error = None;
    while batch.n_envs() > 0 {
        let size = batch.n_envs().min(CHUNK_ENVS);
        let (mut chunk, rest) = batch.split_at(size);
        work(p, &mut chunk, nanos);
        first_error = first_error.or(chunk.error);
        batch = rest;
    }
    first_error
}

/// `work` over the batch on the pool: halves in parallel down to chunks.
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

/// Every stage in order over the chunk's environments.
fn step_chunk(p: &StepParams, b: &mut Batch<'_>, _nanos: &[AtomicU64]) {
    for stage in &STAGES {
        for e in 0..b.n_envs() {
            (stage.run)(p, b, e);
        }
    }
}

/// [`step_chunk`], timing each stage (two clock reads per stage and chunk: about 0.5 µs per chunk,
/// so it is off unless asked for).
fn step_chunk_timed(p: &StepParams, b: &mut Batch<'_>, nanos: &[AtomicU64]) {
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
        if self.timing {
            self.run(actions, &step_chunk_timed)
        } else {
            self.run(actions, &step_chunk)
        }
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

    fn set_stage_timing(&mut self, on: bool) {
        self.timing = on;
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
