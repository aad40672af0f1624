//! The batch layout is data (issue 14): a shader's text holds no batch size and, through the size
//! classes (`backend::wgsl::SizeClasses`), the same text serves most configs, so a second batch
//! on a device compiles no pipeline, whatever its size; and batches whose size is 1 or not a
//! multiple of the workgroup step bit for bit like the CPU.
//!
//! One test in its own binary: the pipeline counter belongs to the process's shared device, which
//! tests running beside it would move.
#![cfg(feature = "gpu")]

mod common;

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
/// assert every state and output column equal, bit for bit, after each step.
fn same_on_both(name: &str, n_envs: usize, steps: usize) {
    let mut cpu = batch(name, n_envs, BackendChoice::Cpu);
    let mut gpu = batch(name, n_envs, BackendChoice::Gpu);
    let holonomic = cpu.params().holonomic != 0;
    let mut rng = RngStream::new(3, 0, 0, 0);
    for step in 0..steps {
        let a = common::gpu::random_actions(&mut rng, n_envs, holonomic);
        cpu.step(Actions::Continuous(&a)).expect("CPU step");
        gpu.step(Actions::Continuous(&a)).expect("GPU step");
        let state = cpu.state().differing_columns(gpu.state());
        let outputs = cpu.outputs().differing_columns(gpu.outputs());
        assert!(
            state.is_empty() && outputs.is_empty(),
            "{name}, {n_envs} environments, step {step}: state columns {state:?} and output \
             columns {outputs:?} differ"
        );
    }
}

#[test]
fn batches_of_any_size_share_compiled_pipelines() {
    let Some(dev) = device() else {
        return;
    };
    // The first batch compiles the step's pipelines (or finds them compiled).
    same_on_both("exp1", 1, 40);
    let compiled = dev.pipeline_builds();
    assert!(compiled > 0, "the first GPU batch compiles its pipelines");
    // Another size, not a multiple of the workgroup (64), and another config of the same size
    // classes: nothing compiles again.
    same_on_both("exp1", 67, 40);
    same_on_both("exp2", 3, 40);
    assert_eq!(
        dev.pipeline_builds(),
        compiled,
        "batches of another size or config compiled pipelines again"
    );
}
