//! The process's shared GPU device lost (`GpuDevice::open` hands one device to every batch): the
//! batches on it fail with `SimError::Device`, and the next batch opens a new device and steps.
//! In a process of its own, since losing the shared device would fail every other GPU test.
//!
//! Needs a GPU adapter (lavapipe will do); without one it says why and passes, unless
//! `REQUIRE_GPU=1`.

#![cfg(feature = "gpu")]

#[path = "common/skip.rs"]
mod skip;

use socnav::backend::BackendChoice;
use socnav::backend::gpu::{AdapterPolicy, GpuDevice};
use socnav::{Actions, BatchEnv, Config, EnvOptions, SimError};

fn batch() -> Result<BatchEnv, SimError> {
    let config = Config::from_name_or_path("exp1")?;
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs: 2,
            seed: 3,
            threads: Some(1),
            backend: BackendChoice::Gpu,
            ..Default::default()
        },
    )?;
    env.reset(None)?;
    Ok(env)
}

#[test]
fn a_lost_shared_device_is_replaced_for_the_next_batch() {
    let shared = match GpuDevice::open(AdapterPolicy::Any) {
        Ok(dev) => dev,
        Err(e) => {
            skip::skip(Some("REQUIRE_GPU"), &format!("no GPU adapter ({e})"));
            return;
        }
    };
    let mut first = batch().expect("a batch on the shared device");
    first.step(Actions::Discrete(&[1, 2])).expect("step");

    shared.device.destroy();
    let lost = first.step(Actions::Discrete(&[1, 2]));
    assert!(matches!(lost, Err(SimError::Device(_))), "{lost:?}");
    assert!(shared.lost().is_some());

    let again = GpuDevice::open(AdapterPolicy::Any).expect("a new shared device");
    assert!(
        again.lost().is_none(),
        "the lost device is not handed out again"
    );
    let mut second = batch().expect("a batch on the new device");
    for t in 0..5 {
        second
            .step(Actions::Discrete(&[t % 7, (t + 3) % 7]))
            .expect("the new batch steps");
    }
    assert!(matches!(
        first.step(Actions::Discrete(&[1, 2])),
        Err(SimError::Device(_))
    ));
}
