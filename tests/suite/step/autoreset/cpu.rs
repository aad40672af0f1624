//! The three autoreset modes of the core (docs/spec.md, step and autoreset;
//! `EnvOptions.autoreset`):
//!
//! - NEXT_STEP: the step after a terminal step returns the new episode's first observation with
//!   reward 0 and no flags, and ignores that step's action;
//! - SAME_STEP: the terminal step returns the finishing step's reward and flags with
//!   `has_final` = 1, `final_obs`/`final_info` hold the finishing step's observation and info,
//!   and `obs` already holds the new episode's first observation;
//! - DISABLED: a finished environment stays frozen, outputs unchanged, until
//!   `reset_envs(mask)` resets exactly the masked environments.
//!
//! Episodes are made to end early: `episode.length = 3` without humans (a truncation at the 4th
//! step, nothing can collide with a robot that stands still), or a fast robot that leaves a room
//! without walls (a termination).

use std::path::Path;

use socnav::spec::info;
use socnav::{Actions, AutoresetMode, BatchEnv, Config, EnvOptions};

/// Episode length of the timeout configs: the 4th step is truncated (tick 4 > 3).
const LENGTH: u32 = 3;

/// Experiment 1 without humans, truncated after `LENGTH` + 1 steps.
fn timeout_config() -> Config {
    let mut c =
        Config::from_file(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/exp1.toml")).unwrap();
    c.episode.length = LENGTH;
    c.counts.dynamic_humans = [0, 0];
    c
}

fn make(config: Config, n_envs: usize, mode: AutoresetMode) -> BatchEnv {
    let options = EnvOptions {
        n_envs,
        seed: 4,
        autoreset: mode,
        ..Default::default()
    };
    let mut env = BatchEnv::new(config, options).unwrap();
    env.reset(None).unwrap();
    env
}

/// Standing still: nothing happens to the robot, the episode can only time out.
fn stop(n: usize) -> Vec<f32> {
    vec![0.0; 3 * n]
}

/// The rows of environment `e` of an output column with `stride` values per environment.
fn row<T: Copy>(column: &[T], stride: usize, e: usize) -> Vec<T> {
    column[e * stride..(e + 1) * stride].to_vec()
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// What a batch of the same config and seed shows after its environments' second reset: the
/// first observation of every environment's second episode.
fn second_episode_start(config: Config, n: usize) -> BatchEnv {
    let mut env = make(config, n, AutoresetMode::NextStep);
    env.reset(None).unwrap();
    env
}

/// Contract: NEXT_STEP.
#[test]
fn next_step_resets_on_the_step_after_the_end() {
    let n = 4;
    let mut env = make(timeout_config(), n, AutoresetMode::NextStep);
    let dim = env.layout().dim;
    for t in 1..=LENGTH {
        env.step(Actions::Continuous(&stop(n))).unwrap();
        let o = env.outputs();
        assert!(
            o.terminated.iter().chain(&o.truncated).all(|&f| f == 0),
            "step {t} must not end the episode"
        );
        assert!(env.state().unwrap().tick.iter().all(|&k| k == t));
    }
    env.step(Actions::Continuous(&stop(n))).unwrap();
    let o = env.outputs();
    for e in 0..n {
        assert_eq!(
            (o.terminated[e], o.truncated[e]),
            (0, 1),
            "env {e}: the 4th step is a truncation"
        );
        assert_eq!(o.info[e * o.strides.info() + info::TIMEOUT], 1.0, "env {e}");
        assert_eq!(o.reward[e], -1.0, "env {e}: the timeout reward");
        assert_eq!(
            o.episode_done[e], 1,
            "env {e}: the episode's statistics are out"
        );
        assert_eq!(
            o.episode[e * o.strides.episode() + 1],
            (LENGTH + 1) as f32,
            "env {e}: episode length"
        );
    }
    // The next step: a full-speed action that must be ignored.
    let drive = [1.0f32, 0.0, 1.0].repeat(n);
    env.step(Actions::Continuous(&drive)).unwrap();
    let fresh = second_episode_start(timeout_config(), n);
    let (o, f) = (env.outputs(), fresh.outputs());
    for e in 0..n {
        assert_eq!(o.reward[e], 0.0, "env {e}: reward of the reset step");
        assert_eq!(
            (
                o.terminated[e],
                o.truncated[e],
                o.episode_done[e],
                o.has_final[e]
            ),
            (0, 0, 0, 0),
            "env {e}"
        );
        let flags = &o.info[e * o.strides.info()..e * o.strides.info() + 7];
        assert!(
            flags.iter().all(|&x| x == 0.0),
            "env {e}: outcome flags of the reset step {flags:?}"
        );
        assert_eq!(
            bits(&row(&o.obs, dim, e)),
            bits(&row(&f.obs, dim, e)),
            "env {e}: first observation"
        );
        assert_eq!(
            row(&o.obs_count, 5, e),
            row(&f.obs_count, 5, e),
            "env {e}: first observation's counts"
        );
        // The action was ignored: the robot stands where the new episode put it, with no command.
        assert_eq!(
            env.get_state(e).unwrap(),
            fresh.get_state(e).unwrap(),
            "env {e}: state of the new episode"
        );
        assert_eq!(env.state().unwrap().tick[e], 0, "env {e}");
        assert_eq!(
            env.state().unwrap().robot_vx[e],
            0.0,
            "env {e}: the reset step moved the robot"
        );
    }
    // And the episode goes on from there.
    env.step(Actions::Continuous(&drive)).unwrap();
    assert!(env.state().unwrap().tick.iter().all(|&k| k == 1));
    assert!(
        env.state().unwrap().robot_vx.iter().all(|&v| v > 0.0),
        "the step after the reset step moves the robot"
    );
}

/// Contract: SAME_STEP. The finishing step is compared with the same step of a NEXT_STEP batch
/// (which shows it as its own outputs) and the new episode with a batch after a second reset.
#[test]
fn same_step_resets_inside_the_finishing_step() {
    let n = 4;
    let mut same = make(timeout_config(), n, AutoresetMode::SameStep);
    let mut next = make(timeout_config(), n, AutoresetMode::NextStep);
    let (dim, ninfo) = (same.layout().dim, socnav::spec::N_INFO);
    for _ in 0..LENGTH {
        same.step(Actions::Continuous(&stop(n))).unwrap();
        next.step(Actions::Continuous(&stop(n))).unwrap();
        assert!(same.outputs().has_final.iter().all(|&h| h == 0));
        assert_eq!(
            bits(&same.outputs().obs),
            bits(&next.outputs().obs),
            "non-final steps agree"
        );
    }
    same.step(Actions::Continuous(&stop(n))).unwrap();
    next.step(Actions::Continuous(&stop(n))).unwrap();
    let fresh = second_episode_start(timeout_config(), n);
    let (o, finishing, f) = (same.outputs(), next.outputs(), fresh.outputs());
    for e in 0..n {
        assert_eq!(o.has_final[e], 1, "env {e}");
        assert_eq!(
            (o.terminated[e], o.truncated[e]),
            (0, 1),
            "env {e}: flags of the finishing step"
        );
        assert_eq!(
            o.reward[e], finishing.reward[e],
            "env {e}: reward of the finishing step"
        );
        assert_eq!(o.reward[e], -1.0, "env {e}");
        assert_eq!(
            bits(&row(&o.final_obs, dim, e)),
            bits(&row(&finishing.obs, dim, e)),
            "env {e}: final_obs"
        );
        assert_eq!(
            row(&o.final_obs_count, 5, e),
            row(&finishing.obs_count, 5, e),
            "env {e}: final counts"
        );
        assert_eq!(
            bits(&row(&o.final_info, ninfo, e)),
            bits(&row(&finishing.info, ninfo, e)),
            "env {e}: final_info"
        );
        assert_eq!(o.final_info[e * ninfo + info::TIMEOUT], 1.0, "env {e}");
        assert_eq!(
            bits(&row(&o.obs, dim, e)),
            bits(&row(&f.obs, dim, e)),
            "env {e}: obs is the new episode's first"
        );
        assert_eq!(row(&o.obs_count, 5, e), row(&f.obs_count, 5, e), "env {e}");
        assert_eq!(
            o.episode_done[e], 1,
            "env {e}: the finished episode's statistics are out"
        );
        assert_eq!(
            same.get_state(e).unwrap(),
            fresh.get_state(e).unwrap(),
            "env {e}: state of the new episode"
        );
    }
    // The next step is an ordinary first step of the new episode.
    let drive = [1.0f32, 0.0, 0.0].repeat(n);
    same.step(Actions::Continuous(&drive)).unwrap();
    let o = same.outputs();
    assert!(
        o.has_final.iter().all(|&h| h == 0),
        "has_final is cleared by the next step"
    );
    assert!(same.state().unwrap().tick.iter().all(|&k| k == 1));
    assert!(
        o.reward
            .iter()
            .all(|&r| r == socnav::Config::default().reward.alive),
        "first step: alive reward only"
    );
}

/// Contract: SAME_STEP with a termination (the robot leaves a room without walls): the
/// terminated flag and the out-of-map reward belong to the finishing step.
#[test]
fn same_step_after_leaving_the_map() {
    let mut c = timeout_config();
    c.episode.length = 200;
    c.room.shape = socnav::config::Shape::NoWalls;
    c.counts.plants = [0, 0];
    // m/s: the fastest robot validation allows at 1 s steps (its diameter a step), so 30 steps
    // cover more than the 10 m room.
    c.robot.max_speed = 0.5;
    let n = 8;
    let mut env = make(c, n, AutoresetMode::SameStep);
    let forward = [1.0f32, 0.0, 0.0].repeat(n);
    let mut left = 0;
    for _ in 0..30 {
        env.step(Actions::Continuous(&forward)).unwrap();
        let o = env.outputs();
        for e in 0..n {
            if o.has_final[e] != 0
                && o.final_info[e * socnav::spec::N_INFO + info::OUT_OF_MAP] == 1.0
            {
                assert_eq!((o.terminated[e], o.truncated[e]), (1, 0), "env {e}");
                assert_eq!(o.reward[e], -1.0, "env {e}: out-of-map reward");
                assert_eq!(env.state().unwrap().tick[e], 0, "env {e}: already reset");
                left += 1;
            }
        }
    }
    // 15 m straight ahead leaves a 10 m room from anywhere in it, unless the goal stops it first.
    assert!(left >= n / 2, "only {left} of {n} robots left the map");
}

/// Contract: DISABLED. Environments finish at different steps (one was reset by mask during the
/// episode); a finished one is frozen (state and outputs unchanged by further steps) while the
/// others go on; `reset_envs` resets exactly the masked environments.
#[test]
fn disabled_freezes_finished_environments_until_reset_by_mask() {
    let n = 4;
    let mut env = make(timeout_config(), n, AutoresetMode::Disabled);
    let (dim, ninfo) = (env.layout().dim, socnav::spec::N_INFO);
    let outputs_of = |env: &BatchEnv, e: usize| {
        let o = env.outputs();
        let mut v = bits(&row(&o.obs, dim, e));
        v.extend(bits(&row(&o.info, ninfo, e)));
        v.extend([o.reward[e].to_bits(), o.terminated[e], o.truncated[e]]);
        v.extend(row(&o.obs_count, 5, e));
        v
    };
    // The state document: everything of the episode (the per-step `stepping` flag of the state
    // columns does change, to say that the frozen environment did not step).
    let state_of = |env: &BatchEnv, e: usize| env.get_state(e).unwrap();
    env.step(Actions::Continuous(&stop(n))).unwrap();
    env.step(Actions::Continuous(&stop(n))).unwrap();
    // Env 1 starts a new episode two steps late.
    let before: Vec<_> = (0..n).map(|e| state_of(&env, e)).collect();
    env.reset_envs(&[false, true, false, false]).unwrap();
    for e in [0, 2, 3] {
        assert_eq!(
            state_of(&env, e),
            before[e],
            "env {e} is not in the mask: unchanged"
        );
    }
    assert_eq!(env.state().unwrap().tick[1], 0);
    env.step(Actions::Continuous(&stop(n))).unwrap();
    env.step(Actions::Continuous(&stop(n))).unwrap(); // ticks 4, 2, 4, 4: envs 0, 2, 3 end
    assert_eq!(env.state().unwrap().tick.to_vec(), vec![4, 2, 4, 4]);
    let finished = [0, 2, 3];
    for e in finished {
        assert_eq!(env.outputs().truncated[e], 1, "env {e}");
    }
    let frozen: Vec<(Vec<u32>, _)> = (0..n)
        .map(|e| (outputs_of(&env, e), state_of(&env, e)))
        .collect();
    let drive = [1.0f32, 0.0, -1.0].repeat(n);
    for k in 0..3 {
        env.step(Actions::Continuous(&drive)).unwrap();
        for e in finished {
            assert!(
                outputs_of(&env, e) == frozen[e].0,
                "env {e}: outputs changed at frozen step {k}"
            );
            assert_eq!(
                state_of(&env, e),
                frozen[e].1,
                "env {e}: state changed at frozen step {k}"
            );
        }
        // Env 1 keeps stepping until its own 4th step, then freezes too.
        assert_eq!(
            env.state().unwrap().tick[1],
            (3 + k as u32).min(LENGTH + 1),
            "env 1 at frozen step {k}"
        );
    }
    assert_eq!(env.outputs().truncated[1], 1);
    // Reset exactly env 0: the others stay as they are, frozen.
    let before: Vec<(Vec<u32>, _)> = (0..n)
        .map(|e| (outputs_of(&env, e), state_of(&env, e)))
        .collect();
    env.reset_envs(&[true, false, false, false]).unwrap();
    assert_eq!(env.state().unwrap().tick[0], 0);
    assert_eq!(
        (env.outputs().reward[0], env.outputs().truncated[0]),
        (0.0, 0)
    );
    assert_ne!(
        outputs_of(&env, 0),
        before[0].0,
        "env 0 shows its new episode"
    );
    for (e, (outputs, state)) in before.iter().enumerate().skip(1) {
        assert!(
            outputs_of(&env, e) == *outputs,
            "env {e} is not in the mask: outputs unchanged"
        );
        assert_eq!(
            state_of(&env, e),
            *state,
            "env {e} is not in the mask: state unchanged"
        );
    }
    env.step(Actions::Continuous(&drive)).unwrap();
    assert_eq!(
        env.state().unwrap().tick.to_vec(),
        vec![1, 4, 4, 4],
        "only env 0 steps"
    );
}
