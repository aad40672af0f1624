//! Metrics (docs/spec.md 8.2): hand-computed cases on exact scenes (the scene helpers and the
//! tolerances: `step/mod.rs`), and a 0.1.1 bug that socnav fixes (docs/fidelity.md).

use crate::common::scene::{load, push, scene, static_human, walker};
use crate::step::{close, info_of, scene_config, step};
use serde_json::json;
use socnav::spec::info;

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
    // Without humans or obstacles: None (NaN), inf and -1 (docs/spec.md 8.2).
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
    let s = env.state().unwrap();
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
