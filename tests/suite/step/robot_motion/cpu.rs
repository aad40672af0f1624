//! Robot motion (docs/spec.md 4.1 steps 2-3): hand-computed cases on exact scenes (the scene
//! helpers and the tolerances: `step/mod.rs`).

use crate::common::scene::{load, scene};
use crate::step::{V, W, close, robot, scene_config, step};
use socnav::Actions;
use socnav::config::Kinematics;

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

/// Contract: the 7 discrete actions of 0.1.1's `DiscreteActions` wrapper (docs/spec.md 9.1).
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
