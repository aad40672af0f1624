//! The reset pool's bookkeeping on the host: which episode each row on the device starts, and
//! the generation of the rows that are missing.
//!
//! The pool holds two rows per environment (`pool_row_of` in `shaders/common/pool_reset.wgsl`):
//! the one its next reset copies, and the one for the reset after that, each in the half of the
//! pool that the parity of the episode counter it starts from chooses. A step consumes at most one
//! row per environment, so after a step in which an environment reset, its other row is the next
//! one, and the freed place must hold the row two episodes ahead before the step after next can
//! consume it. `GpuBackend` therefore generates the *next* rows that are missing (after a
//! `set_state`, new seeds or new constants) before submitting a step, and the rows *two ahead*
//! while the device runs the step, off the critical path.

use crate::error::SimError;
use crate::params::StepParams;
use crate::seeds::next_episode_seed;

use super::GpuStages;
use crate::backend::reset_pool;

/// The episode counter of a row that holds nothing valid.
const NO_ROW: u32 = u32::MAX;

/// Which of an environment's two rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Which {
    /// The row its next reset copies.
    Next,
    /// The row of the reset after that.
    Ahead,
}

/// The pool's rows as the host knows them, and the buffers missing rows are generated in.
#[derive(Debug)]
pub(crate) struct PoolRows {
    n_envs: usize,
    /// Per pool row (`half * n_envs + env`): the episode counter it starts from ([`NO_ROW`]:
    /// none) and the seed of its episode.
    counter: Vec<u32>,
    seed: Vec<u64>,
    /// Rows whose scenario could not be generated: the error, raised when the row is consumed
    /// (the step at which the CPU backend's reset would fail).
    errors: Vec<Option<SimError>>,
    /// The environments whose row is being generated, in order, with the half it goes to.
    envs: Vec<usize>,
    halves: Vec<usize>,
    /// Per environment: the counter and seed its row is generated for (entries of `envs` only).
    for_counter: Vec<u32>,
    for_seed: Vec<u64>,
    words: Vec<u32>,
    /// The generated rows as runs of consecutive environments of one half: (half, first
    /// environment, rows).
    runs: Vec<(usize, usize, usize)>,
    row_words: usize,
}

/// The row an environment at episode counter `counter` resets from: its half and index.
fn place(n_envs: usize, env: usize, counter: u32) -> (usize, usize) {
    let half = ((counter.wrapping_add(1)) & 1) as usize;
    (half, half * n_envs + env)
}

impl PoolRows {
    /// No valid rows yet, for `n_envs` environments of rows of `row_words` words.
    pub(crate) fn new(n_envs: usize, row_words: usize) -> Self {
        Self {
            n_envs,
            counter: vec![NO_ROW; 2 * n_envs],
            seed: vec![0; 2 * n_envs],
            errors: (0..2 * n_envs).map(|_| None).collect(),
            envs: Vec::new(),
            halves: Vec::new(),
            for_counter: vec![0; n_envs],
            for_seed: vec![0; n_envs],
            words: Vec::new(),
            runs: Vec::new(),
            row_words,
        }
    }

    /// Forget every row (the step constants changed, which every row depends on).
    pub(crate) fn invalidate(&mut self) {
        self.counter.fill(NO_ROW);
    }

    /// The counter and seed the `which` row of an environment at counter `counter` with next
    /// seed `next_seed` starts from.
    fn wanted(which: Which, counter: u32, next_seed: u64) -> (u32, u64) {
        match which {
            Which::Next => (counter, next_seed),
            Which::Ahead => (counter.wrapping_add(1), next_episode_seed(next_seed)),
        }
    }

    /// Choose the `which` rows of environments at `counters` with next seeds `next_seeds` that the
    /// pool does not hold; [`Self::generate`] makes them.
    pub(crate) fn select(&mut self, which: Which, counters: &[u32], next_seeds: &[u64]) {
        self.envs.clear();
        self.halves.clear();
        for (e, (&c, &s)) in counters.iter().zip(next_seeds).enumerate() {
            let (c, s) = Self::wanted(which, c, s);
            let (half, at) = place(self.n_envs, e, c);
            if self.counter[at] != c || self.seed[at] != s {
                self.envs.push(e);
                self.halves.push(half);
                self.for_counter[e] = c;
                self.for_seed[e] = s;
            }
        }
    }

    /// How many rows [`Self::select`] chose, for [`Self::generate`] to make.
    pub(crate) fn selected(&self) -> usize {
        self.envs.len()
    }

    /// Generate the selected rows on `pool`'s threads (the caller's alone without one); they are
    /// the pool's from now on, for [`Self::write`] to put on the device.
    pub(crate) fn generate(
        &mut self,
        params: &StepParams,
        pool: Option<&rayon::ThreadPool>,
        scratches: &reset_pool::Scratches,
    ) {
        if self.envs.is_empty() {
            return;
        }
        // Grown, never cleared: `write_rows` writes every word of its rows, so zeroing them first
        // (1.9 MB a step for exp2 at 65,536 environments, on one thread) bought nothing.
        let words = self.envs.len() * self.row_words;
        if self.words.len() < words {
            self.words.resize(words, 0);
        }
        let failed = reset_pool::write_rows(
            params,
            &self.envs,
            &self.for_counter,
            &self.for_seed,
            &mut self.words[..words],
            pool,
            scratches,
        );
        for (&e, &half) in self.envs.iter().zip(&self.halves) {
            let at = half * self.n_envs + e;
            self.counter[at] = self.for_counter[e];
            self.seed[at] = self.for_seed[e];
            self.errors[at] = None;
        }
        for (e, err) in failed {
            let (_, at) = place(self.n_envs, e, self.for_counter[e]);
            self.errors[at] = Some(err);
        }
    }

    /// Hand the generated rows to the device in one write, each run of consecutive environments
    /// of one half copied into its place before the next submitted work
    /// ([`GpuStages::stage_pool_rows`]).
    pub(crate) fn write(&mut self, gpu: &mut GpuStages) {
        self.runs.clear();
        let mut k = 0;
        while k < self.envs.len() {
            let mut end = k + 1;
            while end < self.envs.len()
                && self.envs[end] == self.envs[end - 1] + 1
                && self.halves[end] == self.halves[k]
            {
                end += 1;
            }
            self.runs.push((self.halves[k], self.envs[k], end - k));
            k = end;
        }
        if !self.runs.is_empty() {
            gpu.stage_pool_rows(&self.words[..self.envs.len() * self.row_words], &self.runs);
        }
        self.envs.clear();
        self.halves.clear();
    }

    /// Environment `env`, which was at counter `counter`, consumed its next row: that row's seed
    /// (the episode it now plays) and its scenario error, if it had one.
    pub(crate) fn consumed(&mut self, env: usize, counter: u32) -> (u64, Option<SimError>) {
        let (_, at) = place(self.n_envs, env, counter);
        (self.seed[at], self.errors[at].take())
    }
}
