//! The reset pool's premise (src/backend/reset_pool.rs): a reset is a pure function of the step
//! constants, the environment's next episode seed and its episode counter. For every shipped config, a
//! row generated on a fresh one-environment table equals, word for word, the state and first
//! observation that an in-place reset gives an environment of a rolled-out batch (whose slots
//! hold the previous episode's entities, its counters and caches). A row that leaves its ORCA
//! obstacles to the device (`ObstacleBuild::Deferred`, without their columns) gives the same once
//! copied over the environment and rebuilt, as the GPU backend's reset does.

use crate::common;

use socnav::backend::reset_pool::{RowScratch, row_words, write_row};
use socnav::backend::wgsl::POOL_OBSTACLE_COLUMNS;
use socnav::outputs::Outputs;
use socnav::pipeline::Batch;
use socnav::spec::{ONE_HOT, RECORD};
use socnav::state::BatchState;
use socnav::state::columns::Elem;
use socnav::systems::reset::ObstacleBuild;
use socnav::{Actions, BatchEnv, EnvOptions};

/// The row an in-place reset of environment `e` of `env` produces, in pool layout.
fn reset_in_place(env: &BatchEnv, e: usize) -> Vec<u32> {
    let p = *env.params();
    let mut state = env.state().unwrap().clone();
    let mut out = env.outputs().clone();
    let mut b = Batch {
        s: state.chunk(),
        o: out.chunk(),
        actions: &[],
        sngnn: None,
        error: None,
    };
    socnav::systems::reset::reset_and_observe(&p, &mut b, e);
    assert!(b.error.is_none(), "{:?}", b.error);
    let mut one = BatchState::new(1, *env.caps());
    one.copy_env_from(0, &state, e);
    let mut one_out = Outputs::new(1, *env.layout());
    one_out.copy_env_from(0, &out, e);
    let (mut f, mut u) = (Vec::new(), Vec::new());
    one.pack(&mut f, &mut u);
    let mut row: Vec<u32> = f.iter().map(|v| v.to_bits()).collect();
    row.extend(u);
    // The observation as the device keeps it (src/backend/obs_payload.rs): the robot record
    // whole, then each entity record past its one-hot floats.
    let layout = env.layout();
    let obs: Vec<u32> = one_out.obs.iter().map(|v| v.to_bits()).collect();
    row.extend(&obs[..layout.robot]);
    for record in obs[layout.robot..].chunks_exact(RECORD) {
        row.extend(&record[ONE_HOT..]);
    }
    for col in [
        &one_out.obs_count,
        &one_out.hh_pairs,
        &one_out.hl_pairs,
        &one_out.pair_count,
    ] {
        row.extend(col.iter().copied());
    }
    row
}

/// What the GPU backend's reset leaves environment `e` of `env` (rolled out, before the reset)
/// from `row`, a pool row that leaves its obstacles to the device, in the in-place reset's
/// layout: the row's columns copied over the environment's (every column but the obstacles'
/// [`POOL_OBSTACLE_COLUMNS`], which the environment keeps, their count included), then the
/// obstacles rebuilt, which zeroes the previous episode's tail past the new count.
fn with_obstacles_rebuilt(env: &BatchEnv, e: usize, row: &[u32]) -> Vec<u32> {
    let mut one = BatchState::new(1, *env.caps());
    one.copy_env_from(0, env.state().unwrap(), e);
    let mut w = 0;
    for elem in [Elem::F32, Elem::U32] {
        for (name, of, stride) in one.columns() {
            if of == elem && !POOL_OBSTACLE_COLUMNS.contains(&name) {
                one.column_words_mut(name)
                    .unwrap()
                    .copy_from_slice(&row[w..w + stride]);
                w += stride;
            }
        }
    }
    assert_eq!(
        one.obstacles_dirty[0], 1,
        "a deferred row's obstacles are dirty"
    );
    socnav::systems::orca_obstacles::rebuild_if_dirty(env.params(), &mut one.chunk(), 0);
    assert_eq!(one.obstacles_dirty[0], 0, "rebuilt");
    let (mut f, mut u) = (Vec::new(), Vec::new());
    one.pack(&mut f, &mut u);
    let mut out: Vec<u32> = f.iter().map(|v| v.to_bits()).collect();
    out.extend(u);
    out.extend(&row[w..]);
    out
}

/// Contract: for every config, the generated row of each environment of a batch that has run
/// episodes (with entities, formations and events left over) equals its in-place reset, and a
/// scratch table reused across environments leaves no trace in the next row. A row that leaves
/// its obstacles to the device differs from it in them alone: rebuilt, it equals the in-place
/// reset too.
#[test]
fn rows_equal_in_place_resets() {
    for name in common::config_names() {
        let config = common::load_config(&name);
        let n = 12;
        let mut env = BatchEnv::new(
            config,
            EnvOptions {
                n_envs: n,
                seed: 3,
                ..Default::default()
            },
        )
        .expect("batch");
        env.reset(None).expect("reset");
        let holonomic = env.params().holonomic != 0;
        let mut rng = socnav::rng::RngStream::new(9, 0);
        for _ in 0..90 {
            let a: Vec<f32> = (0..3 * n)
                .map(|k| {
                    let v = 2.0 * rng.next_f32() - 1.0;
                    if k % 3 == 1 && !holonomic { 0.0 } else { v }
                })
                .collect();
            env.step(Actions::Continuous(&a)).expect("step");
        }
        let p = *env.params();
        let words = row_words(*env.caps(), *env.layout(), ObstacleBuild::Now);
        let deferred_words = row_words(*env.caps(), *env.layout(), ObstacleBuild::Deferred);
        let cap = env.caps().obstacle_vertices;
        assert_eq!(
            words - deferred_words,
            4 * cap + 3 * cap + 1,
            "{name}: a deferred row leaves out the obstacles' seven columns and their count"
        );
        // One scratch for all: rows must not depend on what it held before.
        let mut scratch = RowScratch::new(*env.caps(), *env.layout(), ObstacleBuild::Now);
        let mut deferring = RowScratch::new(*env.caps(), *env.layout(), ObstacleBuild::Deferred);
        for e in 0..n {
            let mut row = vec![0u32; words];
            let (episode, seed) = (
                env.state().unwrap().episode[e],
                env.state().unwrap().next_seed(e),
            );
            write_row(&p, e, episode, seed, &mut scratch, &mut row).expect("row");
            let expected = reset_in_place(&env, e);
            assert_eq!(expected.len(), words, "{name}: row length");
            if let Some(k) = (0..words).find(|&k| row[k] != expected[k]) {
                panic!("{name}: env {e}: pool row differs from the in-place reset at word {k}");
            }
            let mut deferred = vec![0u32; deferred_words];
            write_row(&p, e, episode, seed, &mut deferring, &mut deferred).expect("row");
            let rebuilt = with_obstacles_rebuilt(&env, e, &deferred);
            if let Some(k) = (0..words).find(|&k| rebuilt[k] != expected[k]) {
                panic!("{name}: env {e}: deferred row, rebuilt, differs at word {k}");
            }
        }
    }
}
