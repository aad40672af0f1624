//! Property-based fuzzing (proptest): inputs nobody wrote by hand must give a clear error or a
//! valid result, never a panic, a hang or a non-finite output. CI runs each target with a fixed
//! budget and seed; `SOCNAV_FUZZ_CASES=N SOCNAV_FUZZ_SEED=S` runs N cases per target from seed S
//! (a long run: see benches/RESULTS.md).
//! Every failure found becomes a named regression test beside its target.

mod configs;

use proptest::test_runner::{Config, RngSeed};

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
