//! The reset pool: for every environment of a batch, the state its next episode starts with and
//! that state's first observation, as one row of 32-bit words, generated on the host by the same
//! Rust code as the CPU backend's resets (`systems::reset::reset_and_observe`). The GPU backend
//! keeps the rows on the device; its `begin_step`, `autoreset` and `reset` shaders copy a row
//! into an environment instead of generating a scenario (`shaders/common/pool_reset.wgsl`).
//!
//! This works because a reset is a pure function of the step constants, the environment's next
//! episode seed and its episode counter: scenario generation clears every slot and writes every
//! per-environment column (`tests/suite/whole_step/reset_pool.rs` checks a row against an in-place
//! reset of a rolled-out environment for every config). Row layout:
//! [`crate::backend::wgsl::pool_row_words`].
//!
//! A row may leave its ORCA obstacles to the device ([`ObstacleBuild::Deferred`], chosen per
//! [`RowScratch`]): dirty and left out of the row ([`wgsl::POOL_OBSTACLE_COLUMNS`]), they cost
//! the host nothing (their build is about two thirds of a row's instructions, their columns two
//! fifths of its words), and the device rebuilds them after the copy
//! (`backend::schedule::rebuilds_resets`), which gives the bits an in-place reset builds.

use rayon::prelude::*;

use crate::backend::{obs_payload, wgsl};
use crate::error::SimError;
use crate::outputs::Outputs;
use crate::params::StepParams;
use crate::pipeline::Batch;
use crate::spec::ObsLayout;
use crate::state::columns::{Elem, copy_words};
use crate::state::{BatchState, Caps};
use crate::systems::reset::ObstacleBuild;

/// A one-environment table to generate rows in.
#[derive(Debug)]
pub struct RowScratch {
    state: BatchState,
    out: Outputs,
    /// The state packed whole (`soa!`'s `pack_words`), of which the row holds `held`.
    packed: Vec<u32>,
    /// The runs of `packed` a row holds, in order ([`held_runs`]).
    held: Vec<std::ops::Range<usize>>,
    /// Whether the rows hold their ORCA obstacles built, or leave them to the device.
    obstacles: ObstacleBuild,
}

impl RowScratch {
    /// Scratch for environments of capacities `caps` and observation layout `layout`, for rows
    /// whose ORCA obstacles are built as `obstacles` says: [`ObstacleBuild::Now`], the state
    /// exactly as the CPU backend's reset leaves it, or [`ObstacleBuild::Deferred`], its
    /// obstacles dirty and their columns left out of the row, for the device to rebuild after it
    /// copies the row (`GpuPaths::obstacles_after_resets`).
    pub fn new(caps: Caps, layout: ObsLayout, obstacles: ObstacleBuild) -> Self {
        let columns = BatchState::new(0, caps).columns();
        Self {
            state: BatchState::new(1, caps),
            out: Outputs::new(1, layout),
            packed: vec![0; columns.iter().map(|c| c.2).sum()],
            held: held_runs(&columns, obstacles),
            obstacles,
        }
    }
}

/// The runs of a one-environment state packed whole (f32 columns first, then u32 columns, each in
/// declaration order) that a pool row whose obstacles are built as `obstacles` says holds
/// ([`wgsl::pool_holds`]), adjacent columns in one run: a row leaving its obstacles out is then
/// a few copies.
fn held_runs(columns: wgsl::Columns<'_>, obstacles: ObstacleBuild) -> Vec<std::ops::Range<usize>> {
    let mut runs: Vec<std::ops::Range<usize>> = Vec::new();
    let mut at = 0;
    for elem in [Elem::F32, Elem::U32] {
        for &(name, _, stride) in columns.iter().filter(|c| c.1 == elem) {
            if wgsl::pool_holds(name, obstacles) {
                match runs.last_mut() {
                    Some(run) if run.end == at => run.end += stride,
                    _ => runs.push(at..at + stride),
                }
            }
            at += stride;
        }
    }
    runs
}

/// Words of one pool row for environments of capacities `caps` and layout `layout`, whose ORCA
/// obstacles are built as `obstacles` says.
pub fn row_words(caps: Caps, layout: ObsLayout, obstacles: ObstacleBuild) -> usize {
    let s = BatchState::new(0, caps);
    let o = Outputs::new(0, layout);
    wgsl::pool_row_words(&s.columns(), &obs_payload::device_columns(&o), obstacles)
}

/// Write into `row` the pool row of environment `env` (batch index) starting the episode of seed
/// `seed` with episode counter `episode` (the environment's before the reset): the state after
/// `reset_and_observe` (its ORCA obstacles built as `scratch` says), then its first observation
/// (without its one-hot floats, as the device keeps it: [`obs_payload`]). `row` must hold
/// [`row_words`] words.
///
/// # Errors
/// The scenario error of an unsatisfiable configuration, as the CPU backend's reset gives it.
// Out of line, so that a profile names a row's cost: one call a row, against some 35 k
// instructions (callgrind `--toggle-collect='socnav::backend::reset_pool::write_row'`, the full
// name: a pattern that also matches `write_rows` toggles collection off again inside it).
#[inline(never)]
pub fn write_row(
    p: &StepParams,
    env: usize,
    episode: u32,
    seed: u64,
    scratch: &mut RowScratch,
    row: &mut [u32],
) -> Result<(), SimError> {
    let RowScratch {
        state,
        out,
        packed,
        held,
        obstacles,
    } = scratch;
    state.set_next_seed(0, seed);
    state.episode[0] = episode;
    let mut s = state.chunk();
    s.first_env = env;
    let mut o = out.chunk();
    o.first_env = env;
    let mut b = Batch {
        s,
        o,
        actions: &[],
        sngnn: None,
        error: None,
    };
    crate::systems::reset::reset_and_observe_building(p, &mut b, 0, *obstacles);
    if let Some(err) = b.error {
        return Err(err);
    }
    state.pack_words(packed);
    let mut k = 0;
    for run in held.iter() {
        row[k..k + run.len()].copy_from_slice(&packed[run.clone()]);
        k += run.len();
    }
    let payload = out.strides.layout.payload_dim();
    obs_payload::strip_row(
        &out.strides.layout,
        bytemuck::cast_slice(&out.obs),
        &mut row[k..k + payload],
    );
    k += payload;
    for part in [
        &out.obs_count[..],
        &out.hh_pairs,
        &out.hl_pairs,
        &out.pair_count,
    ] {
        copy_words(&mut row[k..k + part.len()], part);
        k += part.len();
    }
    assert_eq!(
        k,
        row.len(),
        "pool row of {k} words in a slot of {}",
        row.len()
    );
    Ok(())
}

/// One [`RowScratch`] per thread that may generate rows (a pool's workers and the caller), kept
/// across calls so that a warm refill allocates nothing.
#[derive(Debug)]
pub struct Scratches(Vec<std::sync::Mutex<RowScratch>>);

impl Scratches {
    /// Scratch tables for `pool`'s threads (or the caller alone), for rows whose obstacles are
    /// built as `obstacles` says ([`RowScratch::new`]).
    pub fn new(
        caps: Caps,
        layout: ObsLayout,
        obstacles: ObstacleBuild,
        pool: Option<&rayon::ThreadPool>,
    ) -> Self {
        let n = pool.map_or(0, rayon::ThreadPool::current_num_threads) + 1;
        Self(
            (0..n)
                .map(|_| std::sync::Mutex::new(RowScratch::new(caps, layout, obstacles)))
                .collect(),
        )
    }

    /// The calling thread's scratch (the last one for a thread outside the pool).
    fn get(&self) -> std::sync::MutexGuard<'_, RowScratch> {
        let k = rayon::current_thread_index().map_or(self.0.len() - 1, |i| i.min(self.0.len() - 1));
        // Each thread takes its own entry, so the lock is never contended; a poisoned one only
        // means an earlier row panicked, and every row overwrites what it reads.
        self.0[k]
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }
}

/// Fill `rows` (one [`row_words`]-word row per entry of `envs`, in order) with the rows of
/// environments `envs` starting the episodes of seeds `seeds[env]` with counters
/// `episodes[env]`, on `pool`'s threads with `scratches`
/// made for that pool: every word of every row, so `rows` need not be cleared first. Returns the
/// environments whose scenario could not be generated, with the error (allocating only then);
/// their rows are zeros.
pub fn write_rows(
    p: &StepParams,
    envs: &[usize],
    episodes: &[u32],
    seeds: &[u64],
    rows: &mut [u32],
    pool: Option<&rayon::ThreadPool>,
    scratches: &Scratches,
) -> Vec<(usize, SimError)> {
    let Some(words) = rows.len().checked_div(envs.len()) else {
        return Vec::new();
    };
    let mut work = || -> Vec<(usize, SimError)> {
        rows.par_chunks_mut(words)
            .zip(envs.par_iter())
            .filter_map(|(row, &env)| {
                let written =
                    write_row(p, env, episodes[env], seeds[env], &mut scratches.get(), row);
                // A failed row holds zeros (no entity, no count), whatever the buffer held.
                written.err().map(|err| {
                    row.fill(0);
                    (env, err)
                })
            })
            .collect()
    };
    match pool {
        Some(pool) => pool.install(work),
        None => work(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    /// Rows need no clearing first: a generated row overwrites every word, and a row whose
    /// scenario finds no free spot is zeros (no entity, no count), whatever the buffer held.
    #[test]
    fn every_word_of_a_row_is_written_and_a_failed_row_is_zeros() {
        let config = Config::from_name_or_path("exp1").unwrap();
        let caps = Caps::from_config(&config);
        let layout = ObsLayout::new(&caps, &config.observation);
        let build = ObstacleBuild::Deferred;
        let words = row_words(caps, layout, build);
        let scratches = Scratches::new(caps, layout, build, None);
        let (envs, episodes, seeds) = ([0, 1], [0; 2], [7, 8]);
        let write = |p: &StepParams, fill: u32| {
            let mut rows = vec![fill; 2 * words];
            let failed = write_rows(p, &envs, &episodes, &seeds, &mut rows, None, &scratches);
            (rows, failed)
        };
        let p = StepParams::new(&config, Default::default());
        let (zeroed, failed) = write(&p, 0);
        assert!(failed.is_empty(), "{failed:?}");
        assert_eq!(write(&p, u32::MAX), (zeroed, Vec::new()));
        // Walkers a room wide: no attempt places them.
        let crowded = StepParams {
            human_radius: 100.0,
            ..p
        };
        let (rows, failed) = write(&crowded, u32::MAX);
        let failed_envs: Vec<usize> = failed.iter().map(|(e, _)| *e).collect();
        assert_eq!(failed_envs, envs);
        assert!(
            failed
                .iter()
                .all(|(_, e)| matches!(e, SimError::Scenario { .. }))
        );
        assert!(rows.iter().all(|&w| w == 0));
    }
}
