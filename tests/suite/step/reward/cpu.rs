//! The DSRNN reward (docs/spec.md 6.2) and the weighted terms beyond 0.1.1: hand-computed cases on
//! exact scenes (the scene helpers and the tolerances: `step/mod.rs`).

use crate::common::scene::{load, push, scene, static_human};
use crate::step::{close, info_of, scene_config, step};
use serde_json::json;
use socnav::BatchEnv;
use socnav::spec::info;

/// Contract: the DSRNN reward's terms on hand-computed scenes (docs/spec.md 6.2; dt = 1 s).
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
