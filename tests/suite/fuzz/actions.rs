//! Actions of any bit pattern: continuous floats drawn from every class (NaN with any payload,
//! infinities, subnormals, ±0, the extremes, ordinary values inside and outside [-1, 1]) and
//! discrete indices of any `u32`. The oracle: a step is refused with `SimError::Action` naming
//! the first bad environment exactly when some action is not finite, a diff-drive robot is given
//! a lateral component, or an index is not one of the 7 actions, and then nothing moves;
//! otherwise it steps cleanly.

use proptest::prelude::*;
use socnav::spec::DISCRETE_ACTIONS;
use socnav::{Actions, AutoresetMode, BatchEnv, Config, SimError};

use super::assert_clean;

const N_ENVS: usize = 3;

/// A float of any class, ordinary values most often.
fn any_float() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -1.5f32..1.5,
        1 => any::<u32>().prop_map(f32::from_bits),
        1 => prop::sample::select(vec![
            f32::NAN, -f32::NAN, f32::from_bits(0x7fc0_0001), f32::from_bits(0xff80_0001),
            f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN, f32::MIN_POSITIVE,
            f32::from_bits(1), -f32::from_bits(1), 0.0, -0.0, 1.0, -1.0, 1e30, -1e30,
        ]),
    ]
}

/// An index of any value, the valid ones most often.
fn any_index() -> impl Strategy<Value = u32> {
    prop_oneof![
        6 => 0u32..7,
        1 => any::<u32>(),
        1 => prop::sample::select(vec![7, 8, u32::MAX, u32::MAX - 6, 1 << 31]),
    ]
}

/// A batch of experiment 3 (diff-drive, or with a holonomic robot), reset at `seed`.
fn batch(holonomic: bool, seed: u64) -> BatchEnv {
    let mut text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/exp3.toml")).unwrap();
    if holonomic {
        text = text.replace(
            r#"kinematics = "diff-drive""#,
            r#"kinematics = "holonomic""#,
        );
    }
    let config = Config::from_toml_str(&text).unwrap();
    super::batch(config, N_ENVS, seed, AutoresetMode::SameStep, 1).unwrap()
}

/// The first environment whose actions the batch must refuse, or `None`.
fn first_bad_continuous(a: &[f32], diff_drive: bool) -> Option<usize> {
    let not_finite = a.iter().position(|v| !v.is_finite()).map(|i| i / 3);
    if not_finite.is_some() {
        return not_finite;
    }
    (0..a.len() / 3).find(|e| diff_drive && a[3 * e + 1] != 0.0)
}

/// Step with `actions`; the outcome must be `expect_bad` (the environment refused) or a clean step.
fn check(env: &mut BatchEnv, actions: Actions<'_>, expect_bad: Option<usize>, context: &str) {
    let before: Vec<_> = (0..N_ENVS).map(|e| env.get_state(e).unwrap()).collect();
    match (env.step(actions), expect_bad) {
        (Ok(()), None) => assert_clean(env, context),
        (Err(SimError::Action { env: bad, message }), Some(e)) => {
            assert_eq!(bad, Some(e), "{message}\n{context}");
            assert!(message.contains(&format!("environment {e}")), "{message}");
            for (k, doc) in before.iter().enumerate() {
                assert_eq!(
                    &env.get_state(k).unwrap(),
                    doc,
                    "a refused step moved environment {k}"
                );
            }
        }
        (outcome, expected) => {
            panic!("expected a refusal of environment {expected:?}, got {outcome:?}\n{context}")
        }
    }
}

proptest! {
    #![proptest_config(super::config(256))]

    #[test]
    fn continuous_actions_of_any_bit_pattern_are_refused_or_step_cleanly(
        holonomic in any::<bool>(),
        seed in 0u64..1000,
        steps in prop::collection::vec(prop::collection::vec(any_float(), 3 * N_ENVS), 1..6),
    ) {
        let mut env = batch(holonomic, seed);
        let diff_drive = env.params().holonomic == 0;
        prop_assert_eq!(diff_drive, !holonomic);
        for a in steps {
            let bad = first_bad_continuous(&a, diff_drive);
            check(&mut env, Actions::Continuous(&a), bad, &format!("{a:?}"));
        }
    }

    #[test]
    fn discrete_actions_of_any_index_are_refused_or_step_cleanly(
        seed in 0u64..1000,
        steps in prop::collection::vec(prop::collection::vec(any_index(), N_ENVS), 1..8),
    ) {
        let mut env = batch(false, seed);
        for a in steps {
            let bad = a.iter().position(|&k| k as usize >= DISCRETE_ACTIONS.len());
            check(&mut env, Actions::Discrete(&a), bad, &format!("{a:?}"));
        }
    }
}

/// Zero-length and wrong-length action buffers are refused with no environment named.
#[test]
fn action_buffers_of_the_wrong_length_are_refused() {
    let mut env = batch(false, 1);
    for a in [vec![], vec![0.0; 3 * N_ENVS - 1], vec![0.0; 3 * N_ENVS + 3]] {
        match env.step(Actions::Continuous(&a)) {
            Err(SimError::Action { env: None, message }) => {
                assert!(message.contains(&format!("got {}", a.len())), "{message}");
            }
            other => panic!("{} floats: {other:?}", a.len()),
        }
    }
    match env.step(Actions::Discrete(&[0; N_ENVS + 1])) {
        Err(SimError::Action { env: None, .. }) => {}
        other => panic!("{other:?}"),
    }
}
