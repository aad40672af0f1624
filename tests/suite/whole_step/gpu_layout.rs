//! The batch layout is data (issue 14): a shader's text holds no batch size and, through the size
//! classes (`backend::wgsl::SizeClasses`), the same text serves every shipped config, so a second batch
//! on a device compiles no pipeline, whatever its size; and batches whose size is 1 or not a
//! multiple of the workgroup step like the CPU (bit for bit on lavapipe, `common::gpu::Twins`).
//!
//! Each batch counts the pipelines it compiled itself (`BatchEnv::pipelines_compiled`), so tests
//! running beside it on the process's shared device do not move the count.

use crate::common;

use common::gpu::{Twins, device};
use socnav::backend::BackendChoice;
use socnav::rng::RngStream;
use socnav::{BatchEnv, Config, EnvOptions};

/// A reset batch of `name` with `n_envs` environments on `backend`.
fn batch(name: &str, n_envs: usize, backend: BackendChoice) -> BatchEnv {
    let mut env = BatchEnv::new(
        Config::from_name_or_path(name).expect("a shipped config"),
        EnvOptions {
            n_envs,
            seed: 7,
            backend,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{name} on {backend:?}: {e}"));
    env.reset(None).expect("reset");
    env
}

/// Step `name` with `n_envs` environments on both backends with the same random actions and
/// compare every state and output column after each step ([`Twins`]: bit for bit on lavapipe, in
/// lockstep elsewhere). Returns how many pipelines the GPU batch compiled.
fn same_on_both(name: &str, n_envs: usize, steps: usize) -> usize {
    let cpu = batch(name, n_envs, BackendChoice::Cpu);
    let gpu = batch(name, n_envs, BackendChoice::Gpu);
    let mut twins = Twins::new(cpu, gpu);
    let holonomic = twins.cpu.params().holonomic != 0;
    let mut rng = RngStream::new(3, 0);
    for _ in 0..steps {
        twins.step(&common::gpu::random_actions(&mut rng, n_envs, holonomic));
    }
    twins.finish(&format!("{name}, {n_envs} environments"));
    twins.gpu.pipelines_compiled()
}

#[test]
fn batches_of_any_size_share_compiled_pipelines() {
    if device().is_none() {
        return;
    }
    // The first batch compiles the step's pipelines (or finds them compiled by a test before).
    same_on_both("exp1", 1, 40);
    // Another size, not a multiple of the workgroup (64), and another config of the same size
    // classes: nothing compiles again.
    for (name, n_envs) in [("exp1", 67), ("exp2", 3)] {
        assert_eq!(
            same_on_both(name, n_envs, 40),
            0,
            "a batch of {n_envs} environments of {name} compiled pipelines again"
        );
    }
}
