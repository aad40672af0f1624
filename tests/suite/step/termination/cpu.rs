//! Termination (docs/spec.md 8.1): the outcome flags and their priority, hand-computed on exact
//! scenes (the scene helpers and the tolerances: `step/mod.rs`).

use crate::common::scene::{load, push, scene, static_human};
use crate::step::{info_of, scene_config, step};
use serde_json::{Value, json};
use socnav::BatchEnv;
use socnav::spec::info;

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
