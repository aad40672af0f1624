//! Faults of the GPU backend, caused for real on whatever adapter there is (lavapipe in CI): a
//! device destroyed under a running batch, and a batch larger than the device can hold. Each
//! gives a typed error, never a panic; the failed batch stays closed with that error, and a batch
//! beside it steps on. (The shared device itself being lost, and the next batch opening a new one,
//! is `tests/gpu_device_lost.rs`: it needs a process of its own.)

use crate::common;

use common::load_config as config;
use socnav::backend::BackendChoice;
use socnav::backend::gpu::{AdapterPolicy, GpuDevice};
use socnav::state::BatchState;
use socnav::{Actions, BatchEnv, EnvOptions, SimError};

fn options(n_envs: usize) -> EnvOptions {
    EnvOptions {
        n_envs,
        seed: 7,
        threads: Some(1),
        backend: BackendChoice::Gpu,
        ..Default::default()
    }
}

/// `steps` steps of `env` with every discrete action in turn, checked clean.
fn steps_cleanly(env: &mut BatchEnv, steps: usize) {
    let n = env.n_envs();
    for t in 0..steps {
        let actions: Vec<u32> = (0..n).map(|e| ((e + t) % 7) as u32).collect();
        env.step(Actions::Discrete(&actions)).expect("step");
        let out = env.outputs();
        assert!(
            out.obs.iter().chain(&out.reward).all(|x| x.is_finite()),
            "step {t}: the outputs are finite"
        );
    }
}

fn assert_lost(what: &str, result: Result<(), SimError>) {
    match result {
        Err(SimError::Device(message)) => assert!(
            message.contains("lost") || message.contains("failed"),
            "{what}: {message}"
        ),
        other => panic!("{what}: expected SimError::Device, got {other:?}"),
    }
}

/// Contract: when the device under a batch is destroyed (what a driver reset or an unplugged GPU
/// does), the batch's next call fails with `SimError::Device` and so does every call after it
/// (the batch is closed: nothing reads a state that can no longer step); no call panics. A batch
/// on another device steps on, and the lost device is reported by `GpuDevice::lost`.
#[test]
fn a_destroyed_device_closes_its_batch_with_a_device_error_and_touches_no_other() {
    let Some(_shared) = common::gpu::device() else {
        return;
    };
    let own = GpuDevice::open_private(AdapterPolicy::Any).expect("a device of its own");
    let mut doomed = BatchEnv::on_device(config("exp1"), options(4), own.clone()).expect("batch");
    doomed.reset(None).expect("reset");
    steps_cleanly(&mut doomed, 3);
    let snapshot = doomed.get_state(0).expect("state before the loss");
    let mut beside = BatchEnv::new(config("exp1"), options(4)).expect("batch on the shared device");
    beside.reset(None).expect("reset");

    own.device.destroy();

    assert_lost(
        "the first step",
        doomed.step(Actions::Discrete(&[0, 1, 2, 3])),
    );
    assert!(own.lost().is_some(), "the loss is recorded");
    assert_lost(
        "the next step",
        doomed.step(Actions::Discrete(&[0, 1, 2, 3])),
    );
    assert_lost("reset", doomed.reset(None));
    assert_lost("reset_envs", doomed.reset_envs(&[true; 4]));
    assert_lost("state", doomed.state().map(|_| ()));
    assert_lost("get_state", doomed.get_state(1).map(|_| ()));
    assert_lost("set_state", doomed.set_state(0, &snapshot));
    assert_lost("set_next_seeds", doomed.set_next_seeds(&[Some(1); 4]));
    drop(doomed);

    steps_cleanly(&mut beside, 5);
    assert_eq!(common::gpu::device().map(|d| d.lost()), Some(None));
}

/// Contract: a batch larger than the device can hold in one binding is refused with
/// `SimError::OutOfMemory` naming the bytes and the adapter (not a validation error at the first
/// step), and a batch made before it on the same device steps on.
#[test]
fn a_batch_larger_than_the_device_is_refused_with_out_of_memory_and_the_batch_beside_it_steps_on() {
    let Some(dev) = common::gpu::device() else {
        return;
    };
    let mut beside = BatchEnv::new(config("exp1"), options(4)).expect("batch");
    beside.reset(None).expect("reset");
    steps_cleanly(&mut beside, 2);

    // Just enough environments that the state's f32 columns overflow one binding.
    let state_f32_words: usize = BatchState::new(1, *beside.caps())
        .columns()
        .iter()
        .filter(|c| c.1 == socnav::state::columns::Elem::F32)
        .map(|c| c.2)
        .sum();
    let max = dev
        .limits
        .max_storage_buffer_binding_size
        .min(dev.limits.max_buffer_size);
    let n_envs = (max / (4 * state_f32_words as u64) + 1) as usize;
    if n_envs * state_f32_words * 4 > 1 << 31 {
        crate::common::skip::skip(
            None,
            &format!(
                "{} binds {max} bytes; a batch beyond it needs more host memory than this test \
                 takes",
                dev.adapter.name
            ),
        );
        return;
    }
    match BatchEnv::new(config("exp1"), options(n_envs)) {
        Err(SimError::OutOfMemory {
            bytes,
            device,
            message,
        }) => {
            assert!(bytes > max, "{bytes} bytes asked, {max} allowed");
            assert_eq!(device.as_deref(), Some(dev.adapter.name.as_str()));
            assert!(
                message.contains(&format!("{n_envs} environments"))
                    && message.contains("use fewer environments"),
                "{message}"
            );
        }
        Err(other) => panic!("expected OutOfMemory, got {other:?}"),
        Ok(_) => panic!("{n_envs} environments were made on {}", dev.adapter.name),
    }
    steps_cleanly(&mut beside, 3);
}
