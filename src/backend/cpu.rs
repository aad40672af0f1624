//! The CPU backend: the reference implementation. Each chunk of [`CHUNK_ENVS`] environments runs
//! every stage of [`STAGES`] in order over its environments, so a chunk's state stays in cache
//! across stages. Environments never read each other, so results do not depend on the number of
//! threads or on the chunking.
//!
//! Threads: the calling thread works too, beside a pool of T − 1 workers; all of them take chunks
//! from a shared queue (no allocation) until the batch is done. A caller that only waited would be
//! woken at the end of every step, which on virtual machines cost up to a third of a 1 ms step;
//! a fixed share per thread would leave threads idle behind one slowed by resets.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

use crate::error::SimError;
use crate::outputs::Outputs;
use crate::params::StepParams;
use crate::pipeline::{Batch, STAGES};
use crate::sngnn::Scorer;
use crate::state::BatchState;

use super::Backend;

/// Environments per chunk: small enough to split the work evenly over the threads, large enough
/// that a chunk's per-stage timing costs nothing next to its work.
pub const CHUNK_ENVS: usize = 32;

/// `threads`, or all cores when `None`.
pub fn resolve_threads(threads: Option<usize>) -> usize {
    threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// A pool of `workers` threads named `<name>-<i>`, or `None` for no workers.
pub fn thread_pool(workers: usize, name: &str) -> Result<Option<rayon::ThreadPool>, SimError> {
    if workers == 0 {
        return Ok(None);
    }
    let name = name.to_owned();
    rayon::ThreadPoolBuilder::new()
        .num_threads(workers)
        .thread_name(move |i| format!("{name}-{i}"))
        .build()
        .map(Some)
        .map_err(|e| SimError::BackendUnavailable(format!("cannot start a thread pool: {e}")))
}

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
    /// The SNGNN-v2 scorer when the reward is SNGNN-v2's.
    sngnn: Option<Arc<Scorer>>,
}

impl CpuBackend {
    /// A backend over `state` and `out` running on `threads` threads (all cores when `None`).
    pub fn new(
        params: StepParams,
        state: BatchState,
        out: Outputs,
        threads: Option<usize>,
    ) -> Result<Self, SimError> {
        let threads = resolve_threads(threads);
        let pool = thread_pool(threads - 1, "socnav-cpu")?;
        let stage_nanos = STAGES.iter().map(|_| AtomicU64::new(0)).collect();
        Ok(Self {
            params,
            state,
            out,
            threads,
            pool,
            stage_nanos,
            timing: false,
            sngnn: None,
        })
    }

    /// The same backend, scoring steps with `sngnn` (the SNGNN-v2 reward needs it).
    pub fn with_sngnn(mut self, sngnn: Option<Arc<Scorer>>) -> Self {
        self.sngnn = sngnn;
        self
    }

    /// The step constants.
    pub fn params(&self) -> &StepParams {
        &self.params
    }

    /// Run `work` over every environment of the batch: the caller and the pool's workers take
    /// chunks from a shared queue until none is left, so a thread slowed by resets (or by a noisy
    /// neighbour on a virtual machine) takes fewer chunks instead of holding the others up.
    fn run(
        &mut self,
        actions: &[f32],
        work: &(dyn Fn(&StepParams, &mut Batch<'_>, &[AtomicU64]) + Sync),
    ) -> Result<(), SimError> {
        let batch = Batch {
            s: self.state.chunk(),
            o: self.out.chunk(),
            actions,
            sngnn: self.sngnn.as_deref(),
            error: None,
        };
        let params = &self.params;
        let nanos = &self.stage_nanos[..];
        let pool = match &self.pool {
            // One chunk is not worth a hand-over to another thread.
            Some(pool) if batch.n_envs() > CHUNK_ENVS => pool,
            _ => {
                let queue = ChunkQueue::new(batch);
                queue.drain(params, nanos, work);
                return queue.result();
            }
        };
        let queue = ChunkQueue::new(batch);
        pool.in_place_scope(|scope| {
            for _ in 0..pool.current_num_threads() {
                scope.spawn(|_| queue.drain(params, nanos, work));
            }
            queue.drain(params, nanos, work);
        });
        queue.result()
    }
}

/// The chunks of a batch still to step, handed out one at a time (safe: each chunk is split off
/// the remainder under the lock, so every thread holds disjoint environments).
struct ChunkQueue<'a> {
    rest: Mutex<Option<Batch<'a>>>,
    error: Mutex<Option<SimError>>,
}

impl<'a> ChunkQueue<'a> {
    fn new(batch: Batch<'a>) -> Self {
        Self {
            rest: Mutex::new(Some(batch)),
            error: Mutex::new(None),
        }
    }

    /// The next chunk of at most [`CHUNK_ENVS`] environments, if any is left.
    fn pull(&self) -> Option<Batch<'a>> {
        // A worker's panic is caught in `drain`, so a poisoned lock holds consistent data.
        let mut rest = self.rest.lock().unwrap_or_else(PoisonError::into_inner);
        let batch = rest.take()?;
        if batch.n_envs() == 0 {
            return None;
        }
        let size = batch.n_envs().min(CHUNK_ENVS);
        let (chunk, remainder) = batch.split_at(size);
        *rest = Some(remainder);
        Some(chunk)
    }

    /// Step chunks until the queue is empty, keeping the first error.
    fn drain(
        &self,
        p: &StepParams,
        nanos: &[AtomicU64],
        work: &(dyn Fn(&StepParams, &mut Batch<'_>, &[AtomicU64]) + Sync),
    ) {
        while let Some(mut chunk) = self.pull() {
            // A panic is a bug; caught here it becomes the call's error instead of unwinding
            // through the thread pool (and aborting a Python interpreter).
            let ran = catch_unwind(AssertUnwindSafe(|| work(p, &mut chunk, nanos)));
            let error = match ran {
                Ok(()) => chunk.error.take(),
                Err(payload) => Some(SimError::Internal(panic_message(payload.as_ref()))),
            };
            if let Some(e) = error {
                self.error
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .get_or_insert(e);
            }
        }
    }

    fn result(self) -> Result<(), SimError> {
        match self
            .error
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner)
        {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// The message a panic was raised with.
pub(crate) fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a worker thread panicked".to_owned())
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
                return Err(SimError::shape(
                    "reset mask",
                    format!(
                        "reset mask has {} entries for {} environments",
                        m.len(),
                        self.state.n_envs
                    ),
                ));
            }
        }
        self.run(&[], &|p, b, _| {
            for e in 0..b.n_envs() {
                let env = b.s.first_env + e;
                if mask.is_none_or(|m| m[env]) {
                    b.s.pending_reset[e] = 0;
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

    fn state(&self) -> Result<&BatchState, SimError> {
        Ok(&self.state)
    }

    fn state_mut(&mut self) -> Result<&mut BatchState, SimError> {
        Ok(&mut self.state)
    }

    fn state_changed(&mut self, env: usize) -> Result<(), SimError> {
        let p = self.params;
        let mut s = self.state.env_chunk(env);
        crate::systems::orca_obstacles::rebuild_edited(&p, &mut s, 0, env)?;
        let mut o = self.out.env_chunk(env);
        crate::systems::observation::write_observation(&p, &mut s, &mut o, 0);
        Ok(())
    }

    fn set_params(&mut self, params: StepParams) {
        self.params = params;
    }

    fn threads(&self) -> usize {
        self.threads
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

    fn device(&self) -> String {
        format!("CPU, {} threads", self.threads)
    }
}
