//! The GPU backend outside the stages (DESIGN.md section 4): the state's and the outputs' trip to
//! the device and back, and the masked reset pass (`shaders/reset.wgsl`, the twin of
//! `CpuBackend::reset`) against the CPU's, bit for bit on lavapipe (the harness:
//! `tests/common/gpu.rs`), and episode seeds through the reset pool.

use crate::common::gpu::*;
use socnav::backend::gpu::GpuStages;
use socnav::outputs::Outputs;
use socnav::state::BatchState;

/// The state and the outputs survive the trip to the device and back bit for bit, every column.
#[test]
fn state_round_trip() {
    let Some(dev) = device() else { return };
    let env = rolled_out(config("exp3"), 64, 60);
    let state = env.state().unwrap().clone();
    let outputs = env.outputs().clone();
    let gpu = GpuStages::new(dev, env.params(), &state, &outputs, &[]).expect("GPU stages");
    let mut back = BatchState::zeroed(state.n_envs, state.strides);
    assert!(!state.differing_columns(&back).is_empty());
    gpu.download_state(&mut back).expect("readback");
    assert!(
        state.differing_columns(&back).is_empty(),
        "state columns changed on the way: {:?}",
        state.differing_columns(&back)
    );
    let mut back = Outputs::zeroed(outputs.n_envs, outputs.strides);
    assert!(!outputs.differing_columns(&back).is_empty());
    gpu.download_outputs(&mut back).expect("readback");
    assert!(
        outputs.differing_columns(&back).is_empty(),
        "output columns changed on the way: {:?}",
        outputs.differing_columns(&back)
    );
}

/// Contract: the masked reset pass (`shaders/reset.wgsl`) equals `CpuBackend::reset` over about
/// half the environments, chained so that reset environments reset again from their next row.
#[test]
fn masked_reset() {
    for name in ["exp2", "stress"] {
        check_parity("reset", config(name), 256, 6, None);
    }
}

/// Contract: episode seeds on the GPU backend (which follows each environment's seed sequence on
/// the host as the device consumes reset-pool rows): autoresets, a seeded reset and seeds named
/// for the next autoreset of some environments give the CPU's episodes, outputs and reported
/// seeds, bit for bit.
#[test]
fn episode_seeds_match_the_cpu() {
    use socnav::backend::BackendChoice;
    use socnav::{Actions, BatchEnv, EnvOptions};
    if device().is_none() {
        return;
    }
    let mut c = config("exp1");
    c.episode.length = 12;
    let n = 67;
    let make = |backend| {
        let mut env = BatchEnv::new(
            c.clone(),
            EnvOptions {
                n_envs: n,
                seed: 5,
                backend,
                ..Default::default()
            },
        )
        .expect("batch");
        env.reset(None).expect("reset");
        env
    };
    let (mut cpu, mut gpu) = (make(BackendChoice::Cpu), make(BackendChoice::Gpu));
    let named: Vec<Option<u64>> = (0..n as u64)
        .map(|e| (e % 3 == 0).then_some(u64::MAX - e))
        .collect();
    let mut rng = socnav::rng::RngStream::new(17, 0);
    let mut reported = std::collections::HashSet::new();
    for t in 0..52 {
        if t == 15 {
            cpu.reset(Some(1 << 40)).expect("reset");
            gpu.reset(Some(1 << 40)).expect("reset");
        }
        if t == 20 {
            cpu.set_next_seeds(&named).expect("seeds");
            gpu.set_next_seeds(&named).expect("seeds");
        }
        let a = random_actions(&mut rng, n, false);
        cpu.step(Actions::Continuous(&a)).expect("step");
        gpu.step(Actions::Continuous(&a)).expect("step");
        let (oc, og) = (cpu.outputs(), gpu.outputs());
        assert_eq!(oc.obs, og.obs, "observations after step {t}");
        assert_eq!(
            oc.episode_done, og.episode_done,
            "episode ends after step {t}"
        );
        for e in (0..n).filter(|&e| oc.episode_done[e] != 0) {
            assert_eq!(
                (oc.episode_seed_lo[e], oc.episode_seed_hi[e]),
                (og.episode_seed_lo[e], og.episode_seed_hi[e]),
                "env {e}: seed of the episode that ended at step {t}"
            );
            reported.insert(socnav::seeds::seed_from_words(
                og.episode_seed_lo[e],
                og.episode_seed_hi[e],
            ));
        }
    }
    for e in 0..n {
        assert_eq!(
            cpu.state().unwrap().episode_seed(e),
            gpu.state().unwrap().episode_seed(e),
            "env {e}"
        );
        assert_eq!(
            cpu.state().unwrap().next_seed(e),
            gpu.state().unwrap().next_seed(e),
            "env {e}"
        );
    }
    // Each named episode was played to its end (the episode running at step 20 ends within 13
    // steps, the named one within 13 more), as were the seeded reset's s + i.
    for seed in named.iter().flatten() {
        assert!(reported.contains(seed), "named seed {seed} never ended");
    }
    assert!(
        reported.contains(&((1 << 40) + 1)),
        "the seeded reset's environment 1"
    );
}
