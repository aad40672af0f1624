//! Property-based fuzzing (proptest): inputs nobody wrote by hand must give a clear error or a
//! valid result, never a panic, a hang or a non-finite output. CI runs each target with a fixed
//! budget and seed; `SOCNAV_FUZZ_CASES=N SOCNAV_FUZZ_SEED=S` runs N cases per target from seed S
//! (a long run: see benches/RESULTS.md).
//! Every failure found becomes a named regression test beside its target.
//!
//! The targets: configs (TOML text and SocNavGym dicts), state documents for `set_state`,
//! actions (any bit pattern), sequences of API calls, and the feasibility of valid configs.

mod actions;
mod configs;
mod documents;
mod feasibility;
mod json;
mod sequences;

use proptest::test_runner::{Config, RngSeed};
use socnav::spec::info_outside_spec;
use socnav::spec::{INFO_KEYS, N_INFO};
use socnav::state::invariants::violations;
use socnav::{AutoresetMode, BatchEnv, EnvOptions, SimError};

/// A target's settings: `SOCNAV_FUZZ_CASES` cases (else `default`), from the fixed seed
/// `SOCNAV_FUZZ_SEED` (else 0, so CI runs the same cases every time; a long run picks another).
fn config(default: u32) -> Config {
    let env = |name: &str| std::env::var(name).ok().and_then(|v| v.parse().ok());
    Config {
        cases: env("SOCNAV_FUZZ_CASES").map_or(default, |n: u64| n as u32),
        rng_seed: RngSeed::Fixed(env("SOCNAV_FUZZ_SEED").unwrap_or(0)),
        failure_persistence: None,
        ..Config::default()
    }
}

/// A CPU batch of `n_envs` environments of `config` on `threads` worker threads, reset at the
/// episodes of seeds `seed`, `seed + 1`, ...
fn batch(
    config: socnav::Config,
    n_envs: usize,
    seed: u64,
    autoreset: AutoresetMode,
    threads: usize,
) -> Result<BatchEnv, SimError> {
    let options = EnvOptions {
        n_envs,
        seed,
        autoreset,
        threads: Some(threads),
        ..Default::default()
    };
    let mut env = BatchEnv::new(config, options)?;
    env.reset(Some(seed))?;
    Ok(env)
}

/// The outputs of the batch's last step or reset are finite (the info values the spec defines
/// as NaN or +inf excepted: `info_outside_spec`) and every environment keeps the state's invariants;
/// `context` names the case in a failure.
fn assert_clean(env: &BatchEnv, context: &str) {
    let out = env.outputs();
    assert!(
        out.obs.iter().all(|v| v.is_finite()),
        "a non-finite observation\n{context}"
    );
    assert!(
        out.reward.iter().all(|v| v.is_finite()),
        "a non-finite reward\n{context}"
    );
    let state = env
        .state()
        .expect("the CPU backend's state is always readable");
    for e in 0..env.n_envs() {
        let row = &out.info[e * N_INFO..(e + 1) * N_INFO];
        let undefined: Vec<_> = info_outside_spec(state, e, row)
            .into_iter()
            .map(|key| (INFO_KEYS[key], row[key]))
            .collect();
        assert!(
            undefined.is_empty(),
            "environment {e}'s info: {undefined:?}\n{context}"
        );
        let broken = violations(state, e);
        assert!(broken.is_empty(), "{broken:?}\n{context}");
    }
}
