//! Observation (docs/spec.md 5): the records in the robot frame, hand-computed on exact scenes (the
//! scene helpers and the tolerances: `step/mod.rs`).

use crate::common::scene::{load, push, records_scene, scene, static_human};
use crate::step::{W, close, scene_config, step};
use serde_json::json;
use socnav::spec::{RECORD, entity};

/// Contract: the 14-float records (docs/spec.md 5.2) in the robot frame: one-hot, position, sin/cos
/// of the relative heading, radius, |v_h - v_r| for humans and (-|v|, -ω) for everything else, the
/// gaze flag; walls cut into segments of 1 m from their left end plus a remainder.
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
