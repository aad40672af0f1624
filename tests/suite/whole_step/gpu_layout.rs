//! The batch layout is data (issue 14): a shader's text holds no batch size and, through the size
//! classes (`backend::wgsl::SizeClasses`), the same text serves every shipped config, so a second batch
//! on a device compiles no pipeline, whatever its size; and batches whose size is 1 or not a
//! multiple of the workgroup step bit for bit like the CPU.
//!
//! Each batch counts the pipelines it compiled itself (`BatchEnv::pipelines_compiled`), so tests
//! running beside it on the process's shared device do not move the count.

use crate::common;

use common::gpu::device;
use socnav::backend::BackendChoice;
use socnav::rng::RngStream;
use socnav::{Actions, BatchEnv, Config, EnvOptions};

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
/// assert every state and output column equal, bit for bit, after each step. Returns how many
/// pipelines the GPU batch compiled.
fn same_on_both(name: &str, n_envs: usize, steps: usize) -> usize {
    let mut cpu = batch(name, n_envs, BackendChoice::Cpu);
    let mut gpu = batch(name, n_envs, BackendChoice::Gpu);
    let holonomic = cpu.params().holonomic != 0;
    let mut rng = RngStream::new(3, 0);
    for step in 0..steps {
        let a = common::gpu::random_actions(&mut rng, n_envs, holonomic);
        cpu.step(Actions::Continuous(&a)).expect("CPU step");
        gpu.step(Actions::Continuous(&a)).expect("GPU step");
        let state = cpu.state().unwrap().differing_columns(gpu.state().unwrap());
        let outputs = cpu.outputs().differing_columns(gpu.outputs());
        assert!(
            state.is_empty() && outputs.is_empty(),
            "{name}, {n_envs} environments, step {step}: state columns {state:?} and output \
             columns {outputs:?} differ"
        );
    }
    gpu.pipelines_compiled()
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
