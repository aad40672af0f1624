//! Sequences of API calls in any order, under each autoreset mode: steps (continuous and
//! discrete), full resets with and without a seed, masked resets, next-seed lists, and
//! `get_state`/`set_state` copies between environments mid-episode. The oracle after every
//! call: clean outputs and invariants, every entity count of an episode conserved while it runs,
//! and the same sequence on one worker thread and on two giving identical bits.

use proptest::prelude::*;
use socnav::state::BatchState;
use socnav::{Actions, AutoresetMode, BatchEnv, Config};

use super::assert_clean;

const N_ENVS: usize = 4;

#[derive(Debug, Clone)]
enum Call {
    /// Continuous actions in [-1, 1] (no lateral component: the robot is diff-drive).
    StepContinuous(Vec<(f32, f32)>),
    StepDiscrete(Vec<u32>),
    Reset(Option<u64>),
    /// A masked reset (bit e resets environment e).
    ResetMask(u8),
    SetNextSeeds(Vec<Option<u64>>),
    /// Environment `to` loads the document of environment `from`.
    Copy {
        from: usize,
        to: usize,
    },
}

fn call() -> impl Strategy<Value = Call> {
    let unit = -1.0f32..=1.0;
    prop_oneof![
        8 => prop::collection::vec((unit.clone(), unit), N_ENVS).prop_map(Call::StepContinuous),
        8 => prop::collection::vec(0u32..7, N_ENVS).prop_map(Call::StepDiscrete),
        1 => prop::option::of(any::<u64>()).prop_map(Call::Reset),
        2 => any::<u8>().prop_map(Call::ResetMask),
        1 => prop::collection::vec(prop::option::of(any::<u64>()), N_ENVS).prop_map(Call::SetNextSeeds),
        2 => (0..N_ENVS, 0..N_ENVS).prop_map(|(from, to)| Call::Copy { from, to }),
    ]
}

fn apply(env: &mut BatchEnv, call: &Call) {
    let outcome = match call {
        Call::StepContinuous(a) => {
            let flat: Vec<f32> = a.iter().flat_map(|&(v, w)| [v, 0.0, w]).collect();
            env.step(Actions::Continuous(&flat))
        }
        Call::StepDiscrete(a) => env.step(Actions::Discrete(a)),
        Call::Reset(seed) => env.reset(*seed),
        Call::ResetMask(bits) => {
            let mask: Vec<bool> = (0..N_ENVS).map(|e| bits >> e & 1 == 1).collect();
            env.reset_envs(&mask)
        }
        Call::SetNextSeeds(seeds) => env.set_next_seeds(seeds),
        Call::Copy { from, to } => env
            .get_state(*from)
            .and_then(|doc| env.set_state(*to, &doc)),
    };
    outcome.unwrap_or_else(|e| panic!("{call:?}: {e:?}"));
}

/// What must not change while an episode runs: its seed and number, and its entity counts.
fn episode_and_counts(s: &BatchState, e: usize) -> ([u32; 3], [u32; 5]) {
    (
        [s.seed_lo[e], s.seed_hi[e], s.episode[e]],
        [
            s.n_humans[e],
            s.n_tables[e],
            s.n_laptops[e],
            s.n_plants[e],
            s.n_walls[e],
        ],
    )
}

fn batch(autoreset: AutoresetMode, threads: usize, seed: u64) -> BatchEnv {
    let config = Config::from_name_or_path("exp3").unwrap();
    super::batch(config, N_ENVS, seed, autoreset, threads).unwrap()
}

proptest! {
    #![proptest_config(super::config(48))]

    #[test]
    fn any_sequence_of_calls_keeps_the_batch_clean_and_deterministic(
        mode in prop::sample::select(vec![
            AutoresetMode::NextStep, AutoresetMode::SameStep, AutoresetMode::Disabled,
        ]),
        seed in any::<u64>(),
        calls in prop::collection::vec(call(), 1..60),
    ) {
        let mut one = batch(mode, 1, seed);
        let mut two = batch(mode, 2, seed);
        for (i, call) in calls.iter().enumerate() {
            let before: Vec<_> = (0..N_ENVS)
                .map(|e| episode_and_counts(one.state().unwrap(), e))
                .collect();
            apply(&mut one, call);
            apply(&mut two, call);
            let context = format!("call {i}: {call:?} ({mode:?}, seed {seed})");
            assert_clean(&one, &context);
            prop_assert_eq!(&one.outputs().obs, &two.outputs().obs, "{}", context);
            prop_assert_eq!(&one.outputs().reward, &two.outputs().reward, "{}", context);
            prop_assert_eq!(
                one.get_state(N_ENVS - 1).unwrap(),
                two.get_state(N_ENVS - 1).unwrap(),
                "{}", context
            );
            let copied_into = match call {
                Call::Copy { to, .. } => Some(*to),
                _ => None,
            };
            for (e, &(episode, counts)) in before.iter().enumerate() {
                let (episode_now, counts_now) = episode_and_counts(one.state().unwrap(), e);
                if episode_now == episode && copied_into != Some(e) {
                    prop_assert_eq!(counts_now, counts, "environment {}: {}", e, context);
                }
            }
        }
    }
}
