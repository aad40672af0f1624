//! CPU/GPU parity of stage `observation` (docs/spec.md, determinism): from the same state and
//! parameters, `shaders/observation.wgsl` must leave the observation, the counts, the interaction
//! pairs and the humans' relative-heading cache bit-identical to the Rust stage on lavapipe, in
//! every shipped config and with every observation option (world frame, the robot's command,
//! a limited field of view and range, noise per type, the padded layout).
//!
//! Runs either chain (the heading cache carries over) or start from states where the robot,
//! humans and objects are scattered over the room with random headings, so that what the sensor
//! sees varies (the harness: `tests/common/gpu.rs`).

use crate::common;

use common::gpu::*;
use socnav::backend::gpu::{GpuDevice, GpuStages};
use socnav::config::{Gaussian, ObsFrame};
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::state::BatchState;
use socnav::{AutoresetMode, Config, StepParams};

/// Robot, humans, laptops and plants scattered over the room with random headings (the robot's
/// exactly 0 now and then), random heading caches, ticks and episodes (new noise draws).
fn scatter(s: &mut BatchState, _: &mut Outputs, _: &StepParams, rng: &mut RngStream) {
    let tau = std::f32::consts::TAU;
    for e in 0..s.n_envs {
        let (hx, hy) = (0.5 * s.map_x[e], 0.5 * s.map_y[e]);
        s.robot_x[e] = uniform(rng, -hx, hx);
        s.robot_y[e] = uniform(rng, -hy, hy);
        s.robot_theta[e] = if rng.next_f32() < 0.1 {
            0.0
        } else {
            uniform(rng, -tau, tau)
        };
        s.robot_vx[e] = uniform(rng, -0.1, 0.1);
        s.robot_w[e] = uniform(rng, -0.4, 0.4);
        s.robot_wvx[e] = uniform(rng, -0.1, 0.1);
        s.robot_wvy[e] = uniform(rng, -0.1, 0.1);
        s.tick[e] = rng.next_u32() % 200;
        s.episode[e] = rng.next_u32() % 5;
        let hb = e * s.strides.humans;
        for i in hb..hb + s.n_humans[e] as usize {
            s.h_x[i] = uniform(rng, -hx, hx);
            s.h_y[i] = uniform(rng, -hy, hy);
            s.h_theta[i] = uniform(rng, -tau, tau);
            s.h_prev_rel_theta[i] = uniform(rng, -3.2, 3.2);
        }
        let lb = e * s.strides.laptops;
        for i in lb..lb + s.n_laptops[e] as usize {
            s.l_x[i] = uniform(rng, -hx, hx);
            s.l_y[i] = uniform(rng, -hy, hy);
        }
        let pb = e * s.strides.plants;
        for i in pb..pb + s.n_plants[e] as usize {
            s.p_x[i] = uniform(rng, -hx, hx);
            s.p_y[i] = uniform(rng, -hy, hy);
        }
    }
}

/// Noise on every type and the robot's goal, with means and deviations of every sign pattern.
fn noisy(mut c: Config) -> Config {
    let n = &mut c.observation.noise;
    n.robot = Gaussian {
        mean: 0.0,
        std: 0.2,
    };
    n.humans = Gaussian {
        mean: 0.1,
        std: 0.3,
    };
    n.laptops = Gaussian {
        mean: -0.05,
        std: 0.0,
    };
    n.tables = Gaussian {
        mean: 0.0,
        std: 0.5,
    };
    n.plants = Gaussian {
        mean: 0.02,
        std: 0.1,
    };
    n.walls = Gaussian {
        mean: 0.0,
        std: 0.25,
    };
    c
}

/// A field of view of 100° and a range of 4 m.
fn partial(mut c: Config) -> Config {
    c.observation.fov = 1.75;
    c.observation.range = Some(4.0);
    c
}

fn world(mut c: Config) -> Config {
    c.observation.frame = ObsFrame::World;
    c
}

/// Both kinds of run, chained and from scattered states, on both of the shader's paths: the
/// observation written into its rows in place and staged slot-major, then moved into the rows
/// (`GpuPaths::stage_observations`; the device's default path first).
fn both(c: Config, n_envs: usize, runs: usize) {
    let (Some(default), Some(other)) = (device(), device_other_paths()) else {
        return;
    };
    for dev in [default, other] {
        let mode = AutoresetMode::NextStep;
        check_parity_on(
            dev.clone(),
            "observation",
            c.clone(),
            mode,
            n_envs,
            runs,
            None,
        );
        check_parity_on(
            dev,
            "observation",
            c.clone(),
            mode,
            n_envs,
            runs,
            Some(scatter),
        );
    }
}

/// Contract: `observation` in every shipped config (plain path: robot frame, everything visible,
/// no noise; walls, tables, laptops, plants, groups and laptop users).
#[test]
fn shipped_configs() {
    for name in ["exp1", "exp2", "exp3", "lroom_mixed", "corridor_mixed"] {
        both(config(name), 256, 10);
    }
    both(config("stress"), 64, 5);
}

/// Contract: the robot's command appended to the robot-frame robot record.
#[test]
fn robot_velocity() {
    for name in ["exp2", "lroom_mixed"] {
        let mut c = config(name);
        c.observation.robot_velocity = true;
        both(c, 256, 10);
    }
}

/// Contract: world-frame records (16-float robot record, world positions, headings and human
/// velocities), alone and with a limited sensor.
#[test]
fn world_frame() {
    for name in ["exp2", "exp3", "lroom_mixed", "corridor_mixed"] {
        both(world(config(name)), 256, 10);
        both(partial(world(config(name))), 256, 10);
    }
}

/// Contract: partial observation (fov, range, each alone and together): visible records
/// compacted in order, counts, and the pairs re-indexed among the visible.
#[test]
fn partial_observation() {
    // The sensor hides some humans and not all of them, so the compaction is exercised.
    let env = rolled_out(partial(config("exp3")), 256, 40);
    let seen: u32 = (0..256).map(|e| env.outputs().obs_count[5 * e]).sum();
    let present: u32 = env.state().unwrap().n_humans.iter().sum();
    assert!(
        0 < seen && seen < present,
        "{seen} of {present} humans seen"
    );
    for name in ["exp1", "exp2", "exp3", "lroom_mixed", "corridor_mixed"] {
        both(partial(config(name)), 256, 10);
        let mut c = config(name);
        c.observation.fov = 3.0;
        both(c, 256, 10);
        let mut c = config(name);
        c.observation.range = Some(2.5);
        both(c, 256, 10);
    }
    both(partial(config("stress")), 64, 5);
}

/// Contract: Gaussian noise per type from stream kind 7, unpadded (records present) and padded
/// (the whole capacity), with a limited sensor and in the world frame.
#[test]
fn noise() {
    for name in ["exp1", "exp2", "exp3", "lroom_mixed", "corridor_mixed"] {
        both(noisy(config(name)), 256, 10);
        both(noisy(partial(config(name))), 256, 10);
        let mut c = noisy(config(name));
        c.observation.padded = true;
        both(c, 256, 10);
    }
    both(noisy(world(partial(config("lroom_mixed")))), 256, 10);
}

/// Contract: the padded layout (no walls), alone, with the command, in the world frame and with
/// a limited sensor.
#[test]
fn padded() {
    for name in ["exp2", "exp3", "lroom_mixed"] {
        let mut c = config(name);
        c.observation.padded = true;
        both(c.clone(), 256, 10);
        c.observation.robot_velocity = true;
        both(c.clone(), 256, 10);
        c.observation.robot_velocity = false;
        both(partial(world(c)), 256, 10);
    }
}

/// Contract: a batch on a device that stages observations holds `n_envs × payload_dim` words more
/// device memory (the staged values in `scratch`) than one on a device that writes rows in place,
/// and says so (`GpuStages::device_bytes`, which out-of-memory errors report); the readback's
/// pieces split the same bytes whatever their number.
#[test]
fn staging_costs_one_observation_per_environment() {
    let n = 67;
    let env = rolled_out(config("exp2"), n, 1);
    let Some((staged, in_place)) =
        bytes_with_and_without(&env, |d| &mut d.paths.stage_observations)
    else {
        return;
    };
    // The staged row is the device's: without the entity records' one-hot floats.
    assert_eq!(
        staged - in_place,
        4 * (n * env.layout().payload_dim()) as u64
    );
}

/// Contract: where the reset pool's rows leave their ORCA obstacles to the device
/// (`GpuPaths::obstacles_after_resets`), its two rows per environment (and the staging
/// buffer's) hold none of the obstacles' columns (`wgsl::POOL_OBSTACLE_COLUMNS`: seven of the
/// obstacle vertices' capacity and their count), and the batch's device memory says so.
#[test]
fn pool_rows_that_leave_their_obstacles_out_shrink_the_pool() {
    let n = 67;
    let env = rolled_out(config("exp2"), n, 1);
    let Some((deferred, built)) =
        bytes_with_and_without(&env, |d| &mut d.paths.obstacles_after_resets)
    else {
        return;
    };
    // Two rows an environment in the pool, and the rows the staging buffer first has room for.
    let rows = 2 * n + socnav::backend::gpu::POOL_STAGING_ROWS;
    let row_words = 7 * env.caps().obstacle_vertices + 1;
    assert_eq!(built - deferred, 4 * (rows * row_words) as u64);
}

/// Device bytes of a batch of `env`'s tables with the observation pass, on the shared device with
/// its `flag` on and with it off; `None` without a device.
fn bytes_with_and_without(
    env: &socnav::BatchEnv,
    flag: fn(&mut GpuDevice) -> &mut bool,
) -> Option<(u64, u64)> {
    let dev = device()?;
    let bytes = |on: bool, mut dev: GpuDevice| {
        *flag(&mut dev) = on;
        let p = *env.params();
        GpuStages::new(
            dev,
            &p,
            env.state().unwrap(),
            env.outputs(),
            &["observation"],
        )
        .expect("GPU stages")
        .device_bytes()
    };
    let with = bytes(true, dev.clone());
    Some((with, bytes(false, dev)))
}

/// Contract: a device that leaves shader functions out (`GpuPaths::leave_out`, for `socnav bench
/// --leave-out`: timings without a function, the results wrong) builds its batches' passes with
/// them returning at once and says so in its description, and a batch refuses a name that none of
/// its shaders defines, naming it.
#[test]
fn functions_left_out_return_at_once_on_the_device() {
    use socnav::{Actions, BatchEnv, EnvOptions};
    let Some(mut dev) = device() else {
        return;
    };
    let n = 8;
    let options = || EnvOptions {
        n_envs: n,
        ..Default::default()
    };
    // Forward and turning (a diff-drive robot: no lateral component).
    let actions = [0.5f32, 0.0, 0.3].repeat(n);
    let mut cpu = BatchEnv::new(config("exp2"), options()).expect("batch");
    cpu.reset(None).expect("reset");
    cpu.step(Actions::Continuous(&actions)).expect("step");
    assert!(
        (0..n).all(|e| cpu.outputs().obs_count[5 * e + 4] > 0),
        "exp2 observes walls"
    );
    // The wall records in the observing lane, where `obs_walls` writes them (on hardware the
    // records dispatch writes them by default: `GpuPaths::records_in_lanes`).
    dev.paths.records_in_lanes = false;
    dev.paths.leave_out = vec!["obs_walls".into()];
    let mut gpu = BatchEnv::on_device(config("exp2"), options(), dev.clone()).expect("batch");
    gpu.reset(None).expect("reset");
    gpu.step(Actions::Continuous(&actions)).expect("step");
    assert!(
        (0..n).all(|e| gpu.outputs().obs_count[5 * e + 4] == 0),
        "obs_walls returned at once: no wall records"
    );
    assert!(
        gpu.device().contains("functions left out: obs_walls"),
        "{}",
        gpu.device()
    );
    dev.paths.leave_out = vec!["obs_walls".into(), "obs_no_such_function".into()];
    let err = BatchEnv::on_device(config("exp2"), options(), dev)
        .expect_err("an unknown name is refused")
        .to_string();
    assert!(
        err.contains("no shader of the batch defines: obs_no_such_function"),
        "{err}"
    );
}
