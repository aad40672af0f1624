//! The shadow robot: a 0.1.1 bug that socnav fixes (docs/fidelity.md), on an exact scene (the
//! scene helpers: `step/mod.rs`).

use crate::common::scene::{load, push, scene};
use crate::step::{scene_config, step};
use serde_json::json;

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
    let s = env.state().unwrap();
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
