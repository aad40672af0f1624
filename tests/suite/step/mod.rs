//! Hand-computed cases for the stages of the step (spec 4-6, 8), on exact scenes loaded with
//! `set_state` from small JSON documents written here (the format of `src/document.rs`).
//!
//! Every expected value is worked out by hand in the comments. Floats are compared with small
//! tolerances because the simulator computes in f32 (ulp 6e-8 at 1, 5e-7 at 5 m) with its own
//! sin/cos/atan2 (`src/math.rs`); the tolerance at each assert says what it covers.

use crate::common;

use std::path::Path;

use common::scene::{load, push, records_scene, scene, static_human, walker};
use serde_json::{Value, json};
use socnav::config::Kinematics;
use socnav::spec::{N_INFO, RECORD, entity, info};
use socnav::{Actions, BatchEnv, Config};

mod autoreset;
mod contacts;
#[cfg(feature = "gpu")]
mod goals;
#[cfg(feature = "gpu")]
mod gpu_stages;
mod human_motion;
mod observation;
mod shadow_robot;
mod sngnn_graph;
mod sngnn_score;
mod social_events;

// ---------------------------------------------------------------------------------------------
// Scene documents
// ---------------------------------------------------------------------------------------------

/// Experiment 1 (10 m square room, dt = 1 s, robot r 0.25, humans r 0.36, plant r 0.4) with
/// room for the scenes below: up to 2 static and 2 walking humans, a standing group of 2, a
/// plant, a table and a free laptop.
fn scene_config() -> Config {
    let mut c =
        Config::from_file(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/exp1.toml")).unwrap();
    c.counts.static_humans = [0, 2];
    c.counts.dynamic_humans = [0, 2];
    c.counts.plants = [0, 1];
    c.counts.tables = [0, 1];
    c.counts.laptops = [0, 1];
    c.counts.standing_groups = [0, 1];
    c.counts.group_size = [2, 2];
    c
}

fn step(env: &mut BatchEnv, actions: &[[f32; 3]]) {
    let flat: Vec<f32> = actions.iter().flatten().copied().collect();
    env.step(Actions::Continuous(&flat)).unwrap();
}

fn info_of(env: &BatchEnv, e: usize, key: usize) -> f32 {
    env.outputs().info[e * N_INFO + key]
}

/// Robot pose (x, y, θ) and command (v_x, v_y, ω) of environment `e`.
fn robot(env: &BatchEnv, e: usize) -> ([f32; 3], [f32; 3]) {
    let s = env.state();
    (
        [s.robot_x[e], s.robot_y[e], s.robot_theta[e]],
        [s.robot_vx[e], s.robot_vy[e], s.robot_w[e]],
    )
}

fn close(what: &str, got: f32, expected: f64, tol: f64) {
    assert!(
        (f64::from(got) - expected).abs() <= tol,
        "{what}: got {got}, expected {expected} (±{tol})"
    );
}

/// 0.1.1's scales of experiment 1: m/s and rad/s for an action of 1.
const V: f64 = 0.1;
const W: f64 = 0.387_596_899;

// ---------------------------------------------------------------------------------------------
// Robot motion (spec 4.1 steps 2-3)
// ---------------------------------------------------------------------------------------------

/// Contract: diff-drive kinematics rotate first, then translate along the *new* heading
/// (semi-implicit Euler): θ' = θ + ω dt, x' = x + v cos θ' dt.
#[test]
fn diff_drive_rotates_then_translates() {
    let mut env = load(
        scene_config(),
        &[
            scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]),
            scene(false, [1.0, -2.0, -1.2], [3.0, 3.0]),
        ],
    );
    step(&mut env, &[[1.0, 0.0, 1.0], [-0.5, 0.0, -0.25]]);
    // env 0: θ' = 0.3876, then 0.1 m along it.
    let (pose, cmd) = robot(&env, 0);
    assert_eq!(cmd, [0.1, 0.0, 0.387_596_9]);
    let t = W;
    // 1e-6: f32 pose arithmetic on values of order 1 plus math.rs's sin/cos error.
    close("x", pose[0], V * t.cos(), 1e-6);
    close("y", pose[1], V * t.sin(), 1e-6);
    close("θ", pose[2], t, 1e-6);
    // Explicit Euler would have moved along θ = 0: y would be 0.
    assert!(pose[1] > 0.03);
    // env 1: v = -0.05 m/s, ω = -0.0969 rad/s from θ = -1.2.
    let (pose, cmd) = robot(&env, 1);
    assert_eq!(cmd, [-0.5 * 0.1, 0.0, -0.25 * 0.387_596_9]);
    let t = -1.2 - 0.25 * W;
    close("x", pose[0], 1.0 - 0.05 * t.cos(), 1e-6);
    close("y", pose[1], -2.0 - 0.05 * t.sin(), 1e-6);
    close("θ", pose[2], t, 1e-6);
}

/// Contract: a holonomic robot also translates along its left axis (θ' + π/2).
#[test]
fn holonomic_translates_sideways() {
    let mut c = scene_config();
    c.robot.kinematics = Kinematics::Holonomic;
    let mut env = load(
        c,
        &[
            scene(false, [1.0, 2.0, std::f64::consts::FRAC_PI_2], [3.0, 3.0]),
            scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]),
        ],
    );
    step(&mut env, &[[0.5, -1.0, 0.0], [0.0, 1.0, 1.0]]);
    // env 0: facing +y; forward 0.05 along +y, lateral -0.1 along its left (-x): (1.1, 2.05).
    let (pose, cmd) = robot(&env, 0);
    assert_eq!(cmd, [0.05, -0.1, 0.0]);
    close("x", pose[0], 1.1, 1e-6);
    close("y", pose[1], 2.05, 1e-6);
    // env 1: turn to 0.3876, then 0.1 m along the new left axis: (-0.1 sin θ', 0.1 cos θ').
    let (pose, _) = robot(&env, 1);
    close("x", pose[0], -V * W.sin(), 1e-6);
    close("y", pose[1], V * W.cos(), 1e-6);
}

/// Contract: actions outside [-1, 1] are scaled, then clipped to the maximum speeds.
#[test]
fn out_of_range_actions_are_clipped() {
    let scenes = vec![scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]); 2];
    let mut env = load(scene_config(), &scenes);
    step(&mut env, &[[3.0, 0.0, -7.0], [-2.0, 0.0, 0.5]]);
    assert_eq!(robot(&env, 0).1, [0.1, 0.0, -0.387_596_9]);
    assert_eq!(robot(&env, 1).1, [-0.1, 0.0, 0.5 * 0.387_596_9]);
    close("x", robot(&env, 0).0[0], V * W.cos(), 1e-6);
    let mut c = scene_config();
    c.robot.kinematics = Kinematics::Holonomic;
    let mut env = load(c, &scenes);
    step(&mut env, &[[0.0, 5.0, 0.0], [0.0, -1.5, 0.0]]);
    assert_eq!(robot(&env, 0).1, [0.0, 0.1, 0.0]);
    assert_eq!(robot(&env, 1).1, [0.0, -0.1, 0.0]);
    close("y", robot(&env, 1).0[1], -0.1, 1e-6);
}

/// Contract: the heading is wrapped to (-π, π] after the rotation.
#[test]
fn heading_wraps() {
    let mut env = load(
        scene_config(),
        &[
            scene(false, [0.0, 0.0, 3.0], [3.0, 3.0]),
            scene(false, [0.0, 0.0, -3.0], [3.0, 3.0]),
        ],
    );
    step(&mut env, &[[1.0, 0.0, 1.0], [1.0, 0.0, -1.0]]);
    let tau = std::f64::consts::TAU;
    for (e, expected) in [(0, 3.0 + W - tau), (1, -3.0 - W + tau)] {
        let (pose, _) = robot(&env, e);
        // 1e-5: wrapping goes through f32 sin/cos/atan2 of an angle near π.
        close("θ", pose[2], expected, 1e-5);
        assert!(
            pose[2] > -std::f32::consts::PI && pose[2] <= std::f32::consts::PI,
            "env {e}: θ {}",
            pose[2]
        );
        close("x", pose[0], V * expected.cos(), 1e-6);
        close("y", pose[1], V * expected.sin(), 1e-6);
    }
}

/// Contract: the 7 discrete actions of 0.1.1's `DiscreteActions` wrapper (spec 9.1).
#[test]
fn discrete_actions_map() {
    // (forward, rotation) of each action: turn left, turn right, forward + left, forward + right,
    // forward, backward, stop.
    let table = [
        (0.0, 1.0),
        (0.0, -1.0),
        (1.0, 1.0),
        (1.0, -1.0),
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, 0.0),
    ];
    let scenes = vec![scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]); 7];
    let mut env = load(scene_config(), &scenes);
    env.step(Actions::Discrete(&[0, 1, 2, 3, 4, 5, 6])).unwrap();
    for (k, (a0, a2)) in table.into_iter().enumerate() {
        let (_, cmd) = robot(&env, k);
        assert_eq!(
            cmd,
            [a0 * 0.1, 0.0, a2 * 0.387_596_9],
            "discrete action {k}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Termination (spec 8.1) and the DSRNN reward (spec 6.2)
// ---------------------------------------------------------------------------------------------

/// The outcome flags of environment `e`, in `INFO_KEYS` order: OUT_OF_MAP, SUCCESS, COLLISION,
/// COLLISION_HUMAN, COLLISION_OBJECT, COLLISION_WALL, TIMEOUT.
fn flags(env: &BatchEnv, e: usize) -> [u8; 7] {
    std::array::from_fn(|k| {
        let v = info_of(env, e, k);
        assert!(v == 0.0 || v == 1.0, "flag {k} is {v}");
        v as u8
    })
}

/// Contract: exactly one outcome, in 0.1.1's priority order: out of map, then success, then
/// collision, then timeout; COLLISION_WALL is reported whatever the outcome. Each scene makes
/// several conditions true at once. The rewards are set apart so that the reward names the
/// branch taken.
#[test]
fn termination_priority() {
    let mut c = scene_config();
    (
        c.reward.reach,
        c.reward.out_of_map,
        c.reward.collision,
        c.reward.timeout,
    ) = (1.0, -1.0, -2.0, -3.0);
    let last_tick = |mut doc: Value, tick: u32| {
        doc["state"]["tick"] = json!(tick);
        doc
    };
    // 0: beyond x = 5 (out of map), 0.3 m from the goal (success), touching a human and the
    //    right wall, at the last tick (timeout).
    let mut out = last_tick(scene(true, [5.2, 0.0, 0.0], [5.2, 0.3]), 200);
    push(&mut out, "humans", static_human(1, 5.2, -0.5, 0.0));
    // 1: 0.32 m from the goal, touching a human (0.54 m < 0.61) and the wall (4.95 > 4.8), at the
    //    last tick.
    let mut success = last_tick(scene(true, [4.7, 0.0, 0.0], [4.6, 0.3]), 200);
    push(&mut success, "humans", static_human(1, 4.5, -0.5, 0.0));
    // 2: touching a human at the last tick.
    let mut collision = last_tick(scene(true, [0.0, 0.0, 0.0], [3.0, 3.0]), 200);
    push(&mut collision, "humans", static_human(1, 0.5, 0.0, 0.0));
    // 3: touching a plant (0.6 m < 0.25 + 0.4).
    let mut plant = scene(true, [0.0, 0.0, 0.0], [3.0, 3.0]);
    push(&mut plant, "plants", json!({"id": 1, "x": 0.6, "y": 0.0}));
    // 4: touching the left wall only (-4.85 < -4.8).
    let wall = scene(true, [-4.6, 0.0, 0.0], [3.0, 3.0]);
    // 5: the last tick only; 6: the tick before the last, nothing.
    let timeout = last_tick(scene(true, [0.0, 0.0, 0.0], [3.0, 3.0]), 200);
    let nothing = last_tick(scene(true, [0.0, 0.0, 0.0], [3.0, 3.0]), 199);
    let scenes = [out, success, collision, plant, wall, timeout, nothing];
    let mut env = load(c, &scenes);
    step(&mut env, &[[0.0; 3]; 7]);
    // (flags, terminated, truncated, reward)
    let expected: [([u8; 7], u32, u32, f32); 7] = [
        ([1, 0, 0, 0, 0, 1, 0], 1, 0, -1.0),
        ([0, 1, 0, 0, 0, 1, 0], 1, 0, 1.0),
        ([0, 0, 1, 1, 0, 0, 0], 1, 0, -2.0),
        ([0, 0, 1, 0, 1, 0, 0], 1, 0, -2.0),
        ([0, 0, 1, 0, 1, 1, 0], 1, 0, -2.0),
        ([0, 0, 0, 0, 0, 0, 1], 0, 1, -3.0),
        ([0, 0, 0, 0, 0, 0, 0], 0, 0, -1e-5),
    ];
    let o = env.outputs();
    for (e, (f, terminated, truncated, reward)) in expected.into_iter().enumerate() {
        assert_eq!(flags(&env, e), f, "scene {e}: outcome flags");
        assert_eq!(
            (o.terminated[e], o.truncated[e]),
            (terminated, truncated),
            "scene {e}"
        );
        assert_eq!(o.reward[e], reward, "scene {e}: reward");
    }
    // The success step's time to reach the goal: tick 201 x dt 1 s.
    assert_eq!(info_of(&env, 1, info::TIME_TO_REACH_GOAL), 201.0);
    assert!(
        info_of(&env, 2, info::TIME_TO_REACH_GOAL).is_nan(),
        "None before success"
    );
}

/// Contract: the DSRNN reward's terms on hand-computed scenes (spec 6.2; dt = 1 s).
#[test]
fn dsrnn_reward_terms() {
    let c = scene_config();
    let alive = f64::from(c.reward.alive);
    // 0: far from everything, driving to a goal 3 m ahead.
    let mut far = scene(false, [0.0, 0.0, 0.0], [3.0, 0.0]);
    push(&mut far, "humans", static_human(1, -3.0, 3.0, 0.0));
    // 1: a human 0.9 m ahead, the robot stands still: clearance 0.9 - 0.36 - 0.25 = 0.29 m.
    let mut near = scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]);
    push(&mut near, "humans", static_human(1, 0.9, 0.0, 0.0));
    // 2: a human 1.2 m ahead, the robot drives at it: after the step it is 1.1 m away and the
    //    relative motion brings it to 1.0 m within dt: predicted clearance 0.39 m (0.49 now).
    let mut approaching = scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]);
    push(&mut approaching, "humans", static_human(1, 1.2, 0.0, 0.0));
    // 3: the human's own velocity counts: 1.0 m ahead, facing the robot at 0.1 m/s (a static
    //    human keeps the speed it is given), robot still: predicted clearance 0.9 - 0.61 = 0.29.
    let mut walking = scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]);
    let mut h = static_human(1, 1.0, 0.0, std::f64::consts::PI);
    h["speed"] = json!(0.1);
    push(&mut walking, "humans", h);
    // 4: as scene 1, one step before the timeout: the terminal step keeps the discomfort info.
    let mut ending = near.clone();
    ending["state"]["tick"] = json!(199);
    let mut env = load(c, &[far, near, approaching, walking, ending]);
    let stop = [0.0f32; 3];
    let forward = [1.0f32, 0.0, 0.0];
    step(&mut env, &[forward, stop, forward, stop, stop]);
    let o = env.outputs();
    // First step: no distance term (the previous distance is unknown), no discomfort.
    assert_eq!(info_of(&env, 0, info::DISTANCE_REWARD), 0.0);
    assert_eq!(info_of(&env, 0, info::DISCOMFORT_DSRNN), 0.0);
    close(
        "alive_reward",
        info_of(&env, 0, info::ALIVE_REWARD),
        alive,
        0.0,
    );
    close("reward", o.reward[0], alive, 1e-9);
    // Discomfort (d_min - 0.6) x 0.5 x dt for the three near scenes. 1e-6: f32 distances of ~1 m.
    for (e, d_min) in [(1, 0.29), (2, 0.39), (3, 0.29)] {
        let disc = (d_min - 0.6) * 0.5;
        close(
            &format!("scene {e} DISCOMFORT_DSRNN"),
            info_of(&env, e, info::DISCOMFORT_DSRNN),
            disc,
            1e-6,
        );
        close(
            &format!("scene {e} reward"),
            o.reward[e],
            disc + alive,
            1e-6,
        );
    }
    step(&mut env, &[forward, stop, [-1.0, 0.0, 0.0], stop, stop]);
    // Scene 0, second step: 2.9 m → 2.8 m to the goal, +5 x 0.1 = 0.5. 1e-5: 5 times the
    // difference of two f32 distances near 3 m (ulp 2.4e-7).
    close(
        "distance_reward",
        info_of(&env, 0, info::DISTANCE_REWARD),
        0.5,
        1e-5,
    );
    close("reward", env.outputs().reward[0], 0.5 + alive, 1e-5);
    // Scene 4 timed out: reward -1, and the reward's info is the previous step's (0.1.1).
    let o = env.outputs();
    assert_eq!((o.truncated[4], o.reward[4]), (1, -1.0));
    close(
        "persisted DISCOMFORT_DSRNN",
        info_of(&env, 4, info::DISCOMFORT_DSRNN),
        -0.155,
        1e-6,
    );
    close(
        "persisted alive_reward",
        info_of(&env, 4, info::ALIVE_REWARD),
        alive,
        0.0,
    );
    // Scene 2 backed off from (0.1, 0) to (0, 0), away from its goal at (3, 3).
    let d_before = (3.0f64 - 0.1).hypot(3.0);
    let d_after = 3.0f64.hypot(3.0);
    close(
        "distance_reward backing off",
        info_of(&env, 2, info::DISTANCE_REWARD),
        -5.0 * (d_after - d_before),
        1e-5,
    );
}

/// Contract: the weighted terms beyond 0.1.1 (`reward.*_weight`) on hand-computed scenes
/// (dt = 1 s, robot radius 0.25 m, human radius 0.36 m, plant radius 0.4 m), each measured as
/// the difference to the reward of the same scene with every weight 0.
#[test]
fn extra_reward_terms() {
    let mut c = scene_config();
    c.reward.personal_space_weight = -2.0;
    c.reward.personal_space_distance = 0.8;
    c.reward.obstacle_weight = -3.0;
    c.reward.obstacle_distance = 0.3;
    c.reward.stalled_weight = -0.25;
    c.reward.acceleration_weight = -0.5;
    // 0: a human 1.2 m ahead of a robot that stands still: its centre is 0.95 m from the
    //    robot's surface, outside 0.8 m: no intrusion; stalled: -0.25; no acceleration.
    let mut stalled = scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]);
    push(&mut stalled, "humans", static_human(1, 1.2, 0.0, 0.0));
    // 1: a human 1 m ahead and the robot drives off at 0.1 m/s to (0.1, 0): 0.9 m apart, 0.65 m
    //    from the surface: intrusion 0.15 m -> -0.3; acceleration 0.1 m/s² -> -0.05.
    let mut close_by = scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]);
    push(&mut close_by, "humans", static_human(1, 1.0, 0.0, 0.0));
    // 2: a plant centred 0.8 m behind a still robot: its surface is 0.4 m from the robot's
    //    centre, 0.15 m from the robot's surface: intrusion 0.15 m -> -0.45; stalled -0.25.
    let mut plant = scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]);
    push(&mut plant, "plants", json!({"id": 1, "x": -0.8, "y": 0.0}));
    // 3: no humans, no obstacles (infinite distances): only the acceleration term.
    let empty = scene(false, [0.0, 0.0, 0.0], [3.0, 3.0]);
    let scenes = [stalled, close_by, plant, empty];
    let stop = [0.0f32; 3];
    let forward = [1.0f32, 0.0, 0.0];
    let actions = [stop, forward, stop, forward];
    let mut plain = load(scene_config(), &scenes);
    let mut weighted = load(c, &scenes);
    let extra = |plain: &BatchEnv, weighted: &BatchEnv, e: usize| {
        weighted.outputs().reward[e] - plain.outputs().reward[e]
    };
    step(&mut plain, &actions);
    step(&mut weighted, &actions);
    // 1e-6: f32 distances of about 1 m.
    let got = |e| extra(&plain, &weighted, e);
    close("stalled", got(0), -0.25, 1e-6);
    close("personal space + acceleration", got(1), -0.3 - 0.05, 1e-6);
    close("obstacle + stalled", got(2), -0.45 - 0.25, 1e-6);
    close(
        "acceleration without humans or obstacles",
        got(3),
        -0.05,
        1e-6,
    );
    // A second step at the same speed: no acceleration; scene 1's robot is at (0.2, 0), 0.8 m
    // from the human's centre, 0.55 m from its surface: intrusion 0.25 m -> -0.5.
    step(&mut plain, &actions);
    step(&mut weighted, &actions);
    let got = |e| extra(&plain, &weighted, e);
    close("personal space, steady speed", got(1), -0.5, 1e-6);
    assert_eq!(got(3), 0.0, "steady speed without neighbours");
}

// ---------------------------------------------------------------------------------------------
// Metrics (spec 8.2)
// ---------------------------------------------------------------------------------------------

/// Contract: PATH_LENGTH, STALLED_TIME (seconds), FAILURE_TO_PROGRESS and the V/A/JERK running
/// statistics on a known command sequence, with dt = 0.5 s so that seconds and steps differ.
#[test]
fn motion_metrics_on_a_known_command_sequence() {
    let mut c = scene_config();
    c.episode.time_step = 0.5;
    let mut env = load(c, &[scene(false, [0.0, 0.0, 0.0], [4.0, 0.0])]);
    // v = 0.1, 0.1, 0.05, 0, -0.1 m/s along the robot's x axis.
    let forwards = [1.0f32, 1.0, 0.5, 0.0, -1.0];
    for a in forwards {
        step(&mut env, &[[a, 0.0, 0.0]]);
    }
    let m = |key| info_of(&env, 0, key);
    // |v| = 0.1, 0.1, 0.05, 0, 0.1; a = Δv/dt = 0.2, 0, -0.1, -0.1, -0.2; j = Δa/dt = 0.4,
    // -0.4, -0.2, 0, -0.2. 1e-6: f32 sums of five values below 1.
    let tol = 1e-6;
    close("PATH_LENGTH", m(info::PATH_LENGTH), 0.5 * 0.35, tol);
    close("STALLED_TIME (s)", m(info::STALLED_TIME), 0.5, tol);
    close(
        "FAILURE_TO_PROGRESS",
        m(info::FAILURE_TO_PROGRESS),
        1.0,
        0.0,
    );
    close("V_MIN", m(info::V_MIN), 0.0, tol);
    close("V_AVG", m(info::V_AVG), 0.07, tol);
    close("V_MAX", m(info::V_MAX), 0.1, tol);
    close("A_MIN", m(info::A_MIN), 0.0, tol);
    close("A_AVG", m(info::A_AVG), 0.12, tol);
    close("A_MAX", m(info::A_MAX), 0.2, tol);
    close("JERK_MIN", m(info::JERK_MIN), 0.0, tol);
    close("JERK_AVG", m(info::JERK_AVG), 0.24, tol);
    close("JERK_MAX", m(info::JERK_MAX), 0.4, tol);
    // Without humans or obstacles: None (NaN), inf and -1 (spec 8.2).
    assert!(m(info::TIME_TO_REACH_GOAL).is_nan());
    assert_eq!(m(info::MINIMUM_DISTANCE_TO_HUMAN), f32::INFINITY);
    assert_eq!(m(info::TIME_TO_COLLISION), -1.0);
    assert_eq!(m(info::MINIMUM_OBSTACLE_DISTANCE), f32::INFINITY);
    assert!(m(info::AVERAGE_OBSTACLE_DISTANCE).is_nan());
    assert_eq!(m(info::PERSONAL_SPACE_COMPLIANCE), 1.0);
}

/// Contract: MINIMUM/AVERAGE_OBSTACLE_DISTANCE over plants (surface), tables and walls (nearest
/// point), from the robot centre, laptops excluded.
#[test]
fn obstacle_distances() {
    let mut doc = scene(true, [0.0, 0.0, 0.0], [-3.0, -3.0]);
    push(&mut doc, "plants", json!({"id": 1, "x": 2.0, "y": 0.0}));
    // 3 m along x, 1.5 m along y: its near edge is at y = 2.25.
    push(
        &mut doc,
        "tables",
        json!({"id": 2, "x": 0.0, "y": 3.0, "theta": 0.0}),
    );
    // A laptop 0.7 m away would be the nearest obstacle if laptops counted.
    push(
        &mut doc,
        "laptops",
        json!({"id": 3, "x": -1.0, "y": 0.0, "theta": 0.0}),
    );
    let mut env = load(scene_config(), &[doc]);
    step(&mut env, &[[0.0; 3]]);
    // plant 2 - 0.4 = 1.6; table 2.25; four walls 4.8 (inner faces).
    // 1e-5: f32 geometry of rotated rectangles at ~5 m (ulp 5e-7, cos(π/2) ≈ -4e-8).
    close(
        "MINIMUM_OBSTACLE_DISTANCE",
        info_of(&env, 0, info::MINIMUM_OBSTACLE_DISTANCE),
        1.6,
        1e-5,
    );
    close(
        "AVERAGE_OBSTACLE_DISTANCE",
        info_of(&env, 0, info::AVERAGE_OBSTACLE_DISTANCE),
        (1.6 + 2.25 + 4.0 * 4.8) / 6.0,
        1e-5,
    );
}

/// Contract: MINIMUM_DISTANCE_TO_HUMAN (centres) and PERSONAL_SPACE_COMPLIANCE, the fraction of
/// steps with (distance - robot radius) >= 0.45 m (human radius not subtracted).
#[test]
fn personal_space_compliance() {
    let mut doc = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
    push(&mut doc, "humans", static_human(1, 0.95, 0.0, 0.0));
    push(&mut doc, "humans", static_human(2, -2.0, 2.0, 0.0));
    let mut env = load(scene_config(), &[doc]);
    // Distances after each step: 0.95, 0.85, 0.75, 0.65 m, i.e. 0.70, 0.60, 0.50, 0.40 m
    // beyond the robot's radius: compliant, compliant, compliant, not.
    let expected = [(0.95, 1.0), (0.85, 1.0), (0.75, 1.0), (0.65, 0.75)];
    for (k, (distance, compliance)) in expected.into_iter().enumerate() {
        let a = if k == 0 { 0.0 } else { 1.0 };
        step(&mut env, &[[a, 0.0, 0.0]]);
        // 1e-6: f32 positions near 1 m.
        close(
            &format!("step {k} MINIMUM_DISTANCE_TO_HUMAN"),
            info_of(&env, 0, info::MINIMUM_DISTANCE_TO_HUMAN),
            distance,
            1e-6,
        );
        close(
            &format!("step {k} PERSONAL_SPACE_COMPLIANCE"),
            info_of(&env, 0, info::PERSONAL_SPACE_COMPLIANCE),
            compliance,
            1e-7,
        );
    }
    assert_eq!(env.outputs().terminated[0], 0, "0.65 m is no collision");
}

/// Contract: TIME_TO_COLLISION = ⌈t/dt⌉ with t = centre distance / approach speed, accepted when
/// the two discs touch at that time, -1 when no human approaches or the approach misses.
#[test]
fn time_to_collision_of_a_human_walking_at_the_robot() {
    // A walker 3.05 m ahead, heading for a goal behind the robot at 0.1 m/s (ORCA in free space:
    // its preferred velocity, the robot is not an ORCA agent in 0.1.1's configs).
    let mut head_on = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
    push(
        &mut head_on,
        "humans",
        walker(1, 3.05, 0.0, std::f64::consts::PI, 0.1, [-4.0, 0.0]),
    );
    // The same walker 1 m to the side: it approaches but passes by.
    let mut passing = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
    push(
        &mut passing,
        "humans",
        walker(1, 3.05, 1.0, std::f64::consts::PI, 0.1, [-4.0, 1.0]),
    );
    // A walker leaving.
    let mut leaving = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
    push(
        &mut leaving,
        "humans",
        walker(1, 1.5, 0.0, 0.0, 0.1, [4.0, 0.0]),
    );
    let mut env = load(scene_config(), &[head_on, passing, leaving]);
    let forward = [1.0f32, 0.0, 0.0];
    step(&mut env, &[forward, forward, [0.0; 3]]);
    let s = env.state();
    let h = s.strides.humans;
    // The walker moved 0.1 m towards its goal and faces it.
    close("walker x", s.h_x[0], 2.95, 1e-6);
    close("walker speed", s.h_speed[0], 0.1, 1e-7);
    close("walker θ", s.h_theta[0], std::f64::consts::PI, 1e-6);
    close("leaving walker x", s.h_x[2 * h], 1.6, 1e-6);
    // Head-on: robot at 0.1, walker at 2.95: 2.85 m closing at 0.2 m/s → t = 14.25 s, when both
    // are at 1.525 m: ⌈14.25⌉ = 15 steps.
    assert_eq!(info_of(&env, 0, info::TIME_TO_COLLISION), 15.0);
    close(
        "MINIMUM_DISTANCE_TO_HUMAN",
        info_of(&env, 0, info::MINIMUM_DISTANCE_TO_HUMAN),
        2.85,
        1e-6,
    );
    // Passing 1 m to the side: at t = |p|/s = 16.0 s they are 1.06 m apart > 0.61: -1.
    assert_eq!(info_of(&env, 1, info::TIME_TO_COLLISION), -1.0);
    assert_eq!(info_of(&env, 2, info::TIME_TO_COLLISION), -1.0);
}

// ---------------------------------------------------------------------------------------------
// Observation (spec 5)
// ---------------------------------------------------------------------------------------------

/// Contract: the 14-float records (spec 5.2) in the robot frame: one-hot, position, sin/cos of
/// the relative heading, radius, |v_h - v_r| for humans and (-|v|, -ω) for everything else,
/// the gaze flag; walls cut into segments of 1 m from their left end plus a remainder.
#[test]
fn observation_records() {
    let half_pi = std::f64::consts::FRAC_PI_2;
    // Robot at (1, 2) facing +y, last command 0.1 m/s and 0.2 rad/s; world → robot frame is
    // (dx, dy) ↦ (dy, -dx). The entities are those of `records_scene`.
    let doc = records_scene();
    let env = load(scene_config(), &[doc]);
    let layout = *env.layout();
    let obs = &env.outputs().obs[..layout.dim];
    let counts = &env.outputs().obs_count[..5];
    assert_eq!(
        counts,
        [2, 1, 1, 1, 5],
        "records per type: humans, laptops, tables, plants, walls"
    );
    // 1e-6: robot-frame transforms of f32 positions within 6 m; cos(π/2) in f32 is -4.4e-8.
    let tol = 1e-6;
    let check = |what: &str, got: &[f32], expected: &[f64]| {
        assert_eq!(got.len(), expected.len());
        for (k, (g, x)) in got.iter().zip(expected).enumerate() {
            close(&format!("{what}[{k}]"), *g, *x, tol);
        }
    };
    check(
        "robot",
        &obs[..9],
        &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 0.0, 0.25],
    );
    let record = |t: usize, k: usize| {
        &obs[layout.offset[t] + k * RECORD..layout.offset[t] + (k + 1) * RECORD]
    };
    // Relative heading 0 - π/2 for everything with heading 0: sin -1, cos 0.
    let (neg_v, neg_w) = (-0.1, -0.2);
    // Human slot 0, the static human at (2, 2): local (0, -1); v_h = 0, |v_r| = 0.1; the robot is
    // behind it: gaze 0. Human slot 1, the walker at (0, 2): local (0, 1);
    // |(0.05, 0) - (0, 0.1)| = 0.1118; the robot is ahead of it: gaze 1. The relative angular
    // speed of a just-loaded scene is 0 (the cache holds the current relative heading).
    check(
        "human 0",
        record(entity::HUMANS, 0),
        &[
            0., 1., 0., 0., 0., 0., 0.0, -1.0, -1.0, 0.0, 0.36, 0.1, 0.0, 0.0,
        ],
    );
    let rel_speed = 0.05f64.hypot(0.1);
    check(
        "human 1",
        record(entity::HUMANS, 1),
        &[
            0., 1., 0., 0., 0., 0., 0.0, 1.0, -1.0, 0.0, 0.36, rel_speed, 0.0, 1.0,
        ],
    );
    let laptop_r = 0.3f64.hypot(0.2);
    check(
        "laptop",
        record(entity::LAPTOPS, 0),
        &[
            0., 0., 0., 1., 0., 0., 1.0, 0.0, -1.0, 0.0, laptop_r, neg_v, neg_w, 0.0,
        ],
    );
    let table_r = 1.5f64.hypot(0.75);
    let (ts, tc) = (0.3 - half_pi).sin_cos();
    check(
        "table",
        record(entity::TABLES, 0),
        &[
            0., 0., 1., 0., 0., 0., 0.0, 3.0, ts, tc, table_r, neg_v, neg_w, 0.0,
        ],
    );
    check(
        "plant",
        record(entity::PLANTS, 0),
        &[
            0., 0., 0., 0., 1., 0., -2.0, 0.0, -1.0, 0.0, 0.4, neg_v, neg_w, 0.0,
        ],
    );
    let wall = |x: f64, y: f64, sin: f64, cos: f64, r: f64| {
        [
            0.,
            0.,
            0.,
            0.,
            0.,
            1.,
            y - 2.0,
            1.0 - x,
            sin,
            cos,
            r,
            neg_v,
            neg_w,
            0.0,
        ]
    };
    check(
        "wall 0 segment 0",
        record(entity::WALLS, 0),
        &wall(0.25, 6.0, -1.0, 0.0, 0.5),
    );
    check(
        "wall 0 segment 1",
        record(entity::WALLS, 1),
        &wall(1.25, 6.0, -1.0, 0.0, 0.5),
    );
    check(
        "wall 0 remainder",
        record(entity::WALLS, 2),
        &wall(2.0, 6.0, -1.0, 0.0, 0.25),
    );
    check(
        "wall 1 segment 0",
        record(entity::WALLS, 3),
        &wall(-3.0, -3.5, 0.0, 1.0, 0.5),
    );
    check(
        "wall 1 segment 1",
        record(entity::WALLS, 4),
        &wall(-3.0, -2.5, 0.0, 1.0, 0.5),
    );
    // Everything past the real records is zero padding.
    for (t, &n) in counts.iter().enumerate() {
        let pad = &obs[layout.offset[t] + n as usize * RECORD
            ..layout.offset[t] + layout.capacity[t] * RECORD];
        assert!(pad.iter().all(|&x| x == 0.0), "padding of type {t}");
    }
}

/// Contract: the humans' relative angular speed is the *wrapped* change of the wrapped relative
/// heading per second (docs/fidelity.md: 0.1.1's unwrapped difference jumps by 2π/dt; fixed),
/// and objects carry -ω.
#[test]
fn relative_angular_speed_is_wrapped() {
    let mut doc = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
    let theta_h = std::f64::consts::PI - 0.1;
    push(&mut doc, "humans", static_human(1, 2.0, 0.0, theta_h));
    push(&mut doc, "plants", json!({"id": 2, "x": -2.0, "y": 0.0}));
    let mut env = load(scene_config(), &[doc]);
    // Turn right at full rate: θ_r = -0.3876. Relative heading π - 0.1 → π + 0.2876, which wraps
    // to -π + 0.2876; the wrapped change is +0.3876 rad in 1 s (0.1.1: -5.8956).
    step(&mut env, &[[0.0, 0.0, -1.0]]);
    let layout = *env.layout();
    let obs = &env.outputs().obs;
    let human = &obs[layout.offset[entity::HUMANS]..][..RECORD];
    let plant = &obs[layout.offset[entity::PLANTS]..][..RECORD];
    // 1e-5: differences of f32 angles near π (ulp 2.4e-7) through wrap_angle.
    close("human relative angular speed", human[12], W, 1e-5);
    let (s, c) = (theta_h + W).sin_cos();
    close("human sin", human[8], s, 1e-5);
    close("human cos", human[9], c, 1e-5);
    close("plant -ω", plant[12], W, 1e-6);
    close("plant -|v|", plant[11], 0.0, 0.0);
}

// ---------------------------------------------------------------------------------------------
// Human motion and contacts (spec 4.1 step 6, 4.6)
// ---------------------------------------------------------------------------------------------

/// Contract: a walker whose velocity is below `speed_threshold` stands still (speed 0) but turns
/// to its velocity's direction; above the threshold it walks.
#[test]
fn speed_threshold_zeroes_a_slow_walker() {
    let mut doc = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
    push(
        &mut doc,
        "humans",
        walker(1, 0.0, 2.0, 2.0, 0.05, [4.0, 2.0]),
    );
    // The walker's ORCA velocity in free space is its preferred velocity, 0.004 m/s towards +x.
    for (threshold, expected_speed) in [(0.005f32, 0.0f64), (0.003, 0.004)] {
        let mut c = scene_config();
        c.human.max_speed = 0.004;
        c.human.speed_threshold = threshold;
        let mut env = load(c, std::slice::from_ref(&doc));
        step(&mut env, &[[0.0; 3]]);
        let s = env.state();
        close(
            &format!("threshold {threshold}: speed"),
            s.h_speed[0],
            expected_speed,
            1e-9,
        );
        close(
            &format!("threshold {threshold}: x"),
            s.h_x[0],
            expected_speed,
            1e-9,
        );
        assert_eq!(s.h_y[0], 2.0, "threshold {threshold}");
        // Heading 2.0 before; the velocity points along +x.
        close(
            &format!("threshold {threshold}: θ"),
            s.h_theta[0],
            0.0,
            1e-7,
        );
    }
}

/// Contract: a human overlapping a plant is pushed out (spec 4.6): penetration
/// k·ln(1 + exp(-(d - r_sum)/k)) with k = 1e-3, force 100·penetration away from the plant; the
/// human turns to the force, takes speed min(|F|·dt, max speed) and moves once more. Lone static
/// humans are never moved; a member of a standing group is.
#[test]
fn contact_pushes_a_human_out_of_a_plant() {
    let mut doc = scene(false, [-3.0, -3.0, 0.0], [3.0, -3.0]);
    push(&mut doc, "plants", json!({"id": 4, "x": 0.0, "y": 0.0}));
    // Slot 0: a static human overlapping the plant on the left. Slots 1, 2: a standing group,
    // member 1 overlapping the plant on the right (0.7 m < 0.36 + 0.4), member 2 clear of it.
    push(&mut doc, "humans", static_human(3, -0.7, 0.0, 0.5));
    for (id, x) in [(1, 0.7), (2, 2.14)] {
        push(
            &mut doc,
            "humans",
            json!({"id": id, "x": x, "y": 0.0, "theta": 1.0, "speed": 0.0, "policy": "orca",
                                        "role": "standing_group", "group": 0}),
        );
    }
    push(
        &mut doc,
        "groups",
        json!({"kind": "standing", "dispersable": false, "members": [1, 2], "centre": [1.42, 0.0]}),
    );
    let mut env = load(scene_config(), &[doc]);
    step(&mut env, &[[0.0; 3]]);
    let s = env.state();
    // Penetration 1e-3·softplus(60) = 0.06 m, force 6 → speed min(6, 0.1) = 0.1 m/s along +x.
    // 1e-6: f32 positions near 1 m.
    close("pushed x", s.h_x[1], 0.8, 1e-6);
    close("pushed y", s.h_y[1], 0.0, 1e-6);
    close("pushed θ", s.h_theta[1], 0.0, 1e-6);
    close("pushed speed", s.h_speed[1], 0.1, 1e-7);
    assert_eq!(
        (s.h_x[2], s.h_y[2], s.h_theta[2], s.h_speed[2]),
        (2.14, 0.0, 1.0, 0.0),
        "member clear of the plant"
    );
    assert_eq!(
        (s.h_x[0], s.h_y[0], s.h_theta[0]),
        (-0.7, 0.0, 0.5),
        "a static human is never moved"
    );
}

/// Regression (found by `tests/golden_perturbed.rs`): a lone static human that touches an object
/// keeps its position and heading but takes the push's speed, as in 0.1.1, whose
/// `handle_collision` assigns `human.speed` while `Human.update_orientation` and `Human.update`
/// return early for a static human. socnav used to leave it untouched. The speed shows wherever
/// a human's velocity does: here the observation's relative speed.
#[test]
fn contact_gives_a_static_human_the_push_speed() {
    let mut doc = scene(false, [-3.0, -3.0, 0.0], [3.0, -3.0]);
    push(&mut doc, "plants", json!({"id": 2, "x": 0.0, "y": 0.0}));
    push(&mut doc, "humans", static_human(1, -0.7, 0.0, 0.5));
    let mut env = load(scene_config(), &[doc]);
    step(&mut env, &[[0.0; 3]]);
    let s = env.state();
    assert_eq!(
        (s.h_x[0], s.h_y[0], s.h_theta[0]),
        (-0.7, 0.0, 0.5),
        "a static human is never moved nor turned"
    );
    // Penetration 1e-3·softplus(60) = 0.06 m, force 6 → speed min(6·1, 0.1) = 0.1 m/s, along the
    // unchanged heading 0.5 rad. 1e-7: f32 products of values below 1.
    close("speed", s.h_speed[0], 0.1, 1e-7);
    close("v_x", s.h_vx[0], 0.1 * 0.5f64.cos(), 1e-7);
    close("v_y", s.h_vy[0], 0.1 * 0.5f64.sin(), 1e-7);
    // The robot stands still: the relative speed is the human's.
    let at = env.layout().offset[entity::HUMANS];
    close(
        "observed relative speed",
        env.outputs().obs[at + 11],
        0.1,
        1e-7,
    );
}

// ---------------------------------------------------------------------------------------------
// 0.1.1 bugs that socnav fixes (docs/fidelity.md)
// ---------------------------------------------------------------------------------------------

/// Contract (fixed 0.1.1 bug): TIME_TO_COLLISION evaluates laptop users too. 0.1.1 re-evaluates
/// a leaked loop variable for them and raises NameError when they are the only humans.
#[test]
fn time_to_collision_covers_a_lone_laptop_user() {
    let mut c = scene_config();
    c.counts.tables = [1, 1];
    c.counts.laptop_users = [0, 1];
    // The robot at the origin drives at 0.1 m/s towards a laptop user 2 m ahead: a laptop at
    // (2.0, 0.7) heading 0, its user 0.7 m along the laptop's −y axis, at (2.0, 0.0).
    let mut doc = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
    push(
        &mut doc,
        "tables",
        json!({"id": 1, "x": 3.0, "y": 3.0, "theta": 0.0}),
    );
    push(
        &mut doc,
        "laptops",
        json!({"id": 2, "x": 2.0, "y": 0.7, "theta": 0.0, "hl": 0}),
    );
    push(
        &mut doc,
        "humans",
        json!({"id": 3, "x": 2.0, "y": 0.0, "theta": std::f64::consts::FRAC_PI_2, "speed": 0.0,
               "policy": "orca", "role": "hl", "hl": 0}),
    );
    push(
        &mut doc,
        "hl_interactions",
        json!({"human": 3, "laptop": 2, "dispersable": false}),
    );
    let mut env = load(c, &[doc]);
    step(&mut env, &[[1.0, 0.0, 0.0]]);
    // After the step the robot is at 0.1 m: 1.9 m closing at 0.1 m/s, centres meet at t = 19 s.
    assert_eq!(info_of(&env, 0, info::TIME_TO_COLLISION), 19.0);
    close(
        "MINIMUM_DISTANCE_TO_HUMAN",
        info_of(&env, 0, info::MINIMUM_DISTANCE_TO_HUMAN),
        1.9,
        1e-6,
    );
}

/// Contract (fixed 0.1.1 bug): the ORCA shadow robot collides with group members it touches.
/// 0.1.1 tests groups and laptop users against the real robot instead, which here stands far
/// away, so it would never flag this collision.
#[test]
fn shadow_robot_collides_with_a_group_member_it_touches() {
    let mut doc = scene(false, [-3.0, -3.0, 0.0], [4.0, 4.0]);
    // A standing group of two; the shadow robot 0.1 m from its first member (contact at 0.61 m;
    // at 0.08 m/s it cannot get clear in one step).
    for (k, (x, y)) in [(1.0, 0.0), (1.0, 0.9)].into_iter().enumerate() {
        push(
            &mut doc,
            "humans",
            json!({"id": 10 + k, "x": x, "y": y, "theta": 0.0, "speed": 0.0, "policy": "orca",
                   "role": "standing_group", "group": 0}),
        );
    }
    push(
        &mut doc,
        "groups",
        json!({"kind": "standing", "dispersable": false, "members": [10, 11], "centre": [1.0, 0.45]}),
    );
    doc["state"]["shadow_robot"] =
        json!({"x": 0.9, "y": 0.0, "theta": 0.0, "vel": [0.0, 0.0, 0.0], "path_length": 0.0});
    let mut env = load(scene_config(), &[doc]);
    step(&mut env, &[[0.0, 0.0, 0.0]]);
    let s = env.state();
    assert_eq!(
        s.shadow_collided[0], 1,
        "the shadow robot touches a group member"
    );
    assert_eq!(
        env.outputs().terminated[0],
        0,
        "the real robot, far away, touches nothing"
    );
}
