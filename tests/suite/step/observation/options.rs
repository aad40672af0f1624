//! The observation options of 0.1.1's wrappers (docs/spec.md 9.1), executed inside the step:
//! world-frame records, the robot's field of view and sensor range, Gaussian sensor noise, and the
//! interaction pairs of `info["interactions"]` (docs/spec.md 5.2), with their recomputation for
//! what is visible.
//!
//! Scenes are written by hand as state documents (the format of `src/document.rs`) and
//! loaded with `set_state`, which rewrites the observation; every expected value is worked out in
//! the comments. Tolerances sit next to their asserts.

use crate::common;
use crate::golden;

use common::scene::{load, push, records_scene, scene, static_human};
use serde_json::{Value, json};
use socnav::config::ObsFrame;
use socnav::outputs::Outputs;
use socnav::spec::{ObsLayout, RECORD, entity};
use socnav::{Actions, BatchEnv, Config, EnvOptions};

// ---------------------------------------------------------------------------------------------
// Scene documents
// ---------------------------------------------------------------------------------------------

/// Experiment 1 (10 m square room, dt = 1 s, robot r 0.25, humans r 0.36, plant r 0.4) with room
/// for the scenes below: 3 static and 2 walking humans, a standing group of 3, a laptop user, two
/// plants, a table and a free laptop.
fn scene_config() -> Config {
    let mut c = Config::from_name_or_path("exp1").unwrap();
    c.counts.static_humans = [0, 3];
    c.counts.dynamic_humans = [0, 2];
    c.counts.plants = [0, 2];
    c.counts.tables = [1, 1];
    c.counts.laptops = [0, 1];
    c.counts.standing_groups = [0, 1];
    c.counts.group_size = [3, 3];
    c.counts.laptop_users = [0, 1];
    c
}

/// Record `k` of entity type `t` in environment `e`.
fn record(env: &BatchEnv, e: usize, t: usize, k: usize) -> &[f32] {
    let l = env.layout();
    let at = e * l.dim + l.offset[t] + k * RECORD;
    &env.outputs().obs[at..at + RECORD]
}

fn counts(env: &BatchEnv, e: usize) -> [u32; 5] {
    env.outputs().obs_count[5 * e..5 * e + 5]
        .try_into()
        .unwrap()
}

fn check(what: &str, got: &[f32], expected: &[f64], tol: f64) {
    assert_eq!(got.len(), expected.len(), "{what}: length");
    for (k, (g, x)) in got.iter().zip(expected).enumerate() {
        assert!(
            (f64::from(*g) - x).abs() <= tol,
            "{what}[{k}]: got {g}, expected {x} (±{tol}); record {got:?}"
        );
    }
}

/// Every record of every type past the count is all-zero padding.
fn assert_padding_zero(env: &BatchEnv, e: usize) {
    let l = env.layout();
    for (t, &n) in counts(env, e).iter().enumerate() {
        for k in n as usize..l.capacity[t] {
            assert!(
                record(env, e, t, k).iter().all(|&x| x == 0.0),
                "env {e}: padding record {k} of type {t}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// World frame (`WorldFrameObservations`)
// ---------------------------------------------------------------------------------------------

/// Contract: with `frame = "world"` the robot record is the 16 floats [one-hot, goal x, goal y,
/// x, y, sin θ, cos θ, v_x, v_y, ω, radius] (the command in the robot frame, as 0.1.1's
/// wrapper); entity records hold world positions and sin/cos of world headings, a human's world
/// velocity at 11-12 and (0, 0) for every other entity, walls included; radius and gaze as in the
/// robot frame; the layout carries the robot record's length.
#[test]
fn world_frame_records() {
    // The scene of the robot-frame test (`records_scene`), written in the world frame.
    let doc = records_scene();
    let mut config = scene_config();
    config.observation.frame = ObsFrame::World;
    let mut env = load(config.clone(), &[doc]);
    let l = *env.layout();
    assert_eq!(l.robot, 16, "world-frame robot record");
    assert_eq!(l, ObsLayout::new(env.caps(), &config.observation));
    assert_eq!(l.offset[entity::HUMANS], 16);
    assert_eq!(counts(&env, 0), [2, 1, 1, 1, 5]);
    // 1e-6: f32 positions within 6 m (ulp 4.8e-7); cos(π/2) in f32 is -4.4e-8.
    let tol = 1e-6;
    check(
        "robot",
        &env.outputs().obs[..16],
        &[
            1., 0., 0., 0., 0., 0., 1.0, 5.0, 1.0, 2.0, 1.0, 0.0, 0.1, 0.0, 0.2, 0.25,
        ],
        tol,
    );
    let human = |x, y, speed: f64, gaze| {
        [
            0., 1., 0., 0., 0., 0., x, y, 0.0, 1.0, 0.36, speed, 0.0, gaze,
        ]
    };
    check(
        "human 0",
        record(&env, 0, entity::HUMANS, 0),
        &human(2.0, 2.0, 0.0, 0.0),
        tol,
    );
    check(
        "human 1",
        record(&env, 0, entity::HUMANS, 1),
        &human(0.0, 2.0, 0.05, 1.0),
        tol,
    );
    let laptop_r = 0.3f64.hypot(0.2);
    check(
        "laptop",
        record(&env, 0, entity::LAPTOPS, 0),
        &[
            0., 0., 0., 1., 0., 0., 1.0, 3.0, 0.0, 1.0, laptop_r, 0.0, 0.0, 0.0,
        ],
        tol,
    );
    let (ts, tc) = 0.3f64.sin_cos();
    check(
        "table",
        record(&env, 0, entity::TABLES, 0),
        &[
            0.,
            0.,
            1.,
            0.,
            0.,
            0.,
            -2.0,
            2.0,
            ts,
            tc,
            1.5f64.hypot(0.75),
            0.0,
            0.0,
            0.0,
        ],
        tol,
    );
    check(
        "plant",
        record(&env, 0, entity::PLANTS, 0),
        &[
            0., 0., 0., 0., 1., 0., 1.0, 0.0, 0.0, 1.0, 0.4, 0.0, 0.0, 0.0,
        ],
        tol,
    );
    let wall = |x, y, sin, cos, r| [0., 0., 0., 0., 0., 1., x, y, sin, cos, r, 0.0, 0.0, 0.0];
    let segments = [
        wall(0.25, 6.0, 0.0, 1.0, 0.5),
        wall(1.25, 6.0, 0.0, 1.0, 0.5),
        wall(2.0, 6.0, 0.0, 1.0, 0.25),
        wall(-3.0, -3.5, 1.0, 0.0, 0.5),
        wall(-3.0, -2.5, 1.0, 0.0, 0.5),
    ];
    for (k, expected) in segments.iter().enumerate() {
        check(
            &format!("wall segment {k}"),
            record(&env, 0, entity::WALLS, k),
            expected,
            tol,
        );
    }
    assert_padding_zero(&env, 0);

    // After a step the walker has moved: its record carries its state, velocity included.
    env.step(Actions::Continuous(&[0.0, 0.0, 0.0])).unwrap();
    let s = env.state().unwrap();
    let h = record(&env, 0, entity::HUMANS, 1);
    let (sn, c) = socnav::math::sin_cos(s.h_theta[1]);
    assert_eq!(
        h[6..13],
        [s.h_x[1], s.h_y[1], sn, c, 0.36, s.h_vx[1], s.h_vy[1]],
        "walker after a step: world position, heading, radius, velocity"
    );
    assert!(s.h_vx[1] != 0.0, "the walker moves");
}

// ---------------------------------------------------------------------------------------------
// Field of view and range (`PartialObservations`)
// ---------------------------------------------------------------------------------------------

/// Contract: with a field of view, a record is kept only if the bearing of its centre in the
/// robot frame lies within ±fov/2; kept records are compacted to the front of their block in
/// order, bit for bit the records of a full view; the counts count them; the rest is zero.
#[test]
fn field_of_view_hides_what_is_behind() {
    // The robot at the origin faces +x with a 180° field of view: it sees x ≥ 0.
    let mut doc = scene(true, [0.0, 0.0, 0.0], [3.0, -3.0]);
    push(&mut doc, "humans", static_human(1, 2.0, 0.5, 0.0)); // ahead
    push(&mut doc, "humans", static_human(2, -2.0, 0.0, 0.0)); // behind
    push(&mut doc, "humans", static_human(3, 1.0, -2.0, 1.0)); // ahead, right
    push(&mut doc, "plants", json!({"id": 4, "x": -1.0, "y": 3.0})); // behind
    push(&mut doc, "plants", json!({"id": 5, "x": 3.0, "y": 3.0})); // ahead
    push(
        &mut doc,
        "tables",
        json!({"id": 6, "x": -3.0, "y": -2.0, "theta": 0.0}),
    ); // behind
    let full = load(scene_config(), std::slice::from_ref(&doc));
    let mut config = scene_config();
    config.observation.fov = std::f32::consts::PI;
    let partial = load(config, &[doc]);
    // Walls: the right wall's 10 segments (x = 4.9) and the 5 segments with x > 0 of each of the
    // top and bottom walls (centres x = 0.5 ... 4.5); none of the left wall.
    assert_eq!(counts(&full, 0), [3, 0, 1, 2, 40]);
    assert_eq!(counts(&partial, 0), [2, 0, 0, 1, 20]);
    for t in [
        entity::HUMANS,
        entity::TABLES,
        entity::PLANTS,
        entity::WALLS,
    ] {
        let ahead: Vec<&[f32]> = (0..counts(&full, 0)[t] as usize)
            .map(|k| record(&full, 0, t, k))
            .filter(|r| r[6] >= 0.0)
            .collect();
        let kept: Vec<&[f32]> = (0..counts(&partial, 0)[t] as usize)
            .map(|k| record(&partial, 0, t, k))
            .collect();
        assert_eq!(kept, ahead, "type {t}: the records ahead, in order");
    }
    assert_padding_zero(&partial, 0);
}

/// Contract: the sensor range keeps a record only if its centre (not its extent) lies within
/// `range` of the robot centre; a full field of view sees behind.
#[test]
fn range_hides_what_is_far() {
    let mut doc = scene(true, [0.0, 0.0, 0.0], [3.0, -3.0]);
    push(&mut doc, "humans", static_human(1, 2.5, 0.0, 0.0)); // 2.5 m
    push(&mut doc, "humans", static_human(2, 0.0, -3.2, 0.0)); // 3.2 m; its disc reaches 2.84 m
    push(&mut doc, "humans", static_human(3, -2.9, 0.0, 0.0)); // 2.9 m, behind
    let mut config = scene_config();
    config.observation.range = Some(3.0);
    let env = load(config, &[doc]);
    // The walls' nearest segment centres are 4.9 m away.
    assert_eq!(counts(&env, 0), [2, 0, 0, 0, 0]);
    check(
        "first kept",
        &record(&env, 0, entity::HUMANS, 0)[6..8],
        &[2.5, 0.0],
        1e-6,
    );
    check(
        "second kept",
        &record(&env, 0, entity::HUMANS, 1)[6..8],
        &[-2.9, 0.0],
        1e-6,
    );
    assert_padding_zero(&env, 0);
}

/// Contract: visibility is decided in the robot frame even when the world frame is written.
#[test]
fn world_frame_keeps_what_the_robot_sees() {
    // The robot at the origin faces -x with a 180° field of view: it sees world x ≤ 0.
    let mut doc = scene(false, [0.0, 0.0, std::f64::consts::PI], [3.0, -3.0]);
    push(&mut doc, "humans", static_human(1, 2.0, 0.0, 0.0)); // behind the robot
    push(&mut doc, "humans", static_human(2, -2.0, 0.5, 0.0)); // ahead of it
    let mut config = scene_config();
    config.observation.frame = ObsFrame::World;
    config.observation.fov = std::f32::consts::PI;
    let env = load(config, &[doc]);
    assert_eq!(counts(&env, 0), [1, 0, 0, 0, 0]);
    assert_eq!(
        record(&env, 0, entity::HUMANS, 0)[6..8],
        [-2.0, 0.5],
        "world position"
    );
    assert_padding_zero(&env, 0);
}

// ---------------------------------------------------------------------------------------------
// Interactions (`info["interactions"]`)
// ---------------------------------------------------------------------------------------------

/// A scene with a static human (slot 0), a standing group of 3 (slots 1-3), a laptop user
/// (slot 4) at laptop slot 1, a free laptop (slot 0) and a table, at the given positions.
fn interaction_scene(
    robot: [f64; 3],
    lone: [f64; 2],
    members: [[f64; 2]; 3],
    user: [f64; 2],
    laptops: [[f64; 2]; 2],
) -> Value {
    let mut doc = scene(false, robot, [4.0, 4.0]);
    push(&mut doc, "humans", static_human(1, lone[0], lone[1], 0.0));
    for (k, m) in members.iter().enumerate() {
        push(
            &mut doc,
            "humans",
            json!({"id": 2 + k, "x": m[0], "y": m[1], "theta": 0.0, "speed": 0.0, "policy": "orca",
                   "role": "standing_group", "group": 0}),
        );
    }
    push(
        &mut doc,
        "groups",
        json!({"kind": "standing", "dispersable": false, "members": [2, 3, 4], "centre": members[0]}),
    );
    push(
        &mut doc,
        "humans",
        json!({"id": 5, "x": user[0], "y": user[1], "theta": std::f64::consts::FRAC_PI_2, "speed": 0.0,
               "policy": "orca", "role": "hl", "hl": 0}),
    );
    push(
        &mut doc,
        "laptops",
        json!({"id": 6, "x": laptops[0][0], "y": laptops[0][1], "theta": 0.0}),
    );
    push(
        &mut doc,
        "laptops",
        json!({"id": 7, "x": laptops[1][0], "y": laptops[1][1], "theta": 0.0, "hl": 0}),
    );
    push(
        &mut doc,
        "hl_interactions",
        json!({"human": 5, "laptop": 7, "dispersable": false}),
    );
    push(
        &mut doc,
        "tables",
        json!({"id": 8, "x": 3.5, "y": 3.5, "theta": 0.0}),
    );
    doc
}

/// The pairs of environment `e`: (human-human, human-laptop), each as a list of (i, j); the
/// padding past the counts is checked to be zero.
fn pairs(o: &Outputs, e: usize) -> (Vec<[u32; 2]>, Vec<[u32; 2]>) {
    let (hh, hl) = (o.strides.hh(), o.strides.hl());
    let n = &o.pair_count[2 * e..2 * e + 2];
    let list = |col: &[u32], stride: usize, n: u32| {
        let row = &col[e * stride..(e + 1) * stride];
        assert!(
            row[2 * n as usize..].iter().all(|&x| x == 0),
            "pair padding"
        );
        row[..2 * n as usize]
            .chunks_exact(2)
            .map(|p| [p[0], p[1]])
            .collect::<Vec<_>>()
    };
    (list(&o.hh_pairs, hh, n[0]), list(&o.hl_pairs, hl, n[1]))
}

/// Contract (docs/spec.md 5.2): every ordered pair of a group's members, (i, j) then (j, i) for
/// i < j in member order, as indices into the `humans` records; each laptop user's (human index,
/// laptop index). The group of 3 gives 6 pairs, the laptop user 1.
#[test]
fn interactions_of_a_group_and_a_laptop_user() {
    let doc = interaction_scene(
        [0.0, 0.0, 0.0],
        [1.0, -3.0],
        [[2.0, 1.0], [-1.0, 1.0], [2.0, 2.0]],
        [3.0, -1.0],
        [[-3.0, 3.0], [3.0, -0.3]],
    );
    let env = load(scene_config(), &[doc]);
    let (hh, hl) = pairs(env.outputs(), 0);
    assert_eq!(hh, [[1, 2], [2, 1], [1, 3], [3, 1], [2, 3], [3, 2]]);
    assert_eq!(hl, [[4, 1]]);
    // humans × (group_size - 1) = 9 × 2 human-human pairs, one per laptop user.
    assert_eq!(env.layout().pairs, [18, 1]);
}

/// Contract: with a limited view the pairs index the visible, compacted records, as 0.1.1's
/// `PartialObservations` recomputes them: a group keeps the pairs of its visible members; a
/// laptop user's pair needs both the human and the laptop visible.
#[test]
fn interactions_of_what_is_visible() {
    // Facing +x with a 180° view: the lone human (1, -3), members 1 and 3 and the user (3, -1)
    // are visible (records 0, 1, 2, 3), member 2 at (-1, 1) is not; the free laptop (-3, 3) is
    // hidden, so the user's laptop (3, -0.3) is laptop record 0.
    let members = [[2.0, 1.0], [-1.0, 1.0], [2.0, 2.0]];
    let view = interaction_scene(
        [0.0, 0.0, 0.0],
        [1.0, -3.0],
        members,
        [3.0, -1.0],
        [[-3.0, 3.0], [3.0, -0.3]],
    );
    // The same with the user's laptop moved to (3.3, -0.3), 3.31 m away, beyond a 3.2 m range
    // that still holds the user (3.16 m), the lone human (3.16 m) and members 1 and 3.
    let far_laptop = interaction_scene(
        [0.0, 0.0, 0.0],
        [1.0, -3.0],
        members,
        [3.0, -1.0],
        [[-3.0, 3.0], [3.3, -0.3]],
    );
    let mut config = scene_config();
    config.observation.fov = std::f32::consts::PI;
    let env = load(config.clone(), &[view]);
    assert_eq!(counts(&env, 0)[..2], [4, 1]);
    let (hh, hl) = pairs(env.outputs(), 0);
    assert_eq!(hh, [[1, 2], [2, 1]]);
    assert_eq!(hl, [[3, 0]]);

    config.observation.range = Some(3.2);
    let env = load(config, &[far_laptop]);
    assert_eq!(counts(&env, 0)[..2], [4, 0]);
    let (hh, hl) = pairs(env.outputs(), 0);
    assert_eq!(hh, [[1, 2], [2, 1]]);
    assert!(hl.is_empty(), "the user's laptop is out of range: {hl:?}");
}

/// Contract: the pairs equal 0.1.1's `info["interactions"]` on every recorded state of the golden
/// episodes with groups and laptop users (the state the step's outputs describe, loaded with
/// `set_state`).
#[test]
fn interactions_match_the_golden_episodes() {
    let Some(dir) = golden::golden_dir_or_skip("interactions_match_the_golden_episodes") else {
        return;
    };
    let episodes = golden::load_episodes(&dir, None);
    assert!(
        !episodes.is_empty(),
        "no golden episodes in {}",
        dir.display()
    );
    let (mut states, mut with_pairs) = (0, 0);
    for (name, ep) in &episodes {
        let config = match golden::config_for(ep) {
            Ok(config) => config,
            Err(e) => {
                println!("SKIP {name}: {}", e.lines().next().unwrap_or_default());
                continue;
            }
        };
        // The pairs do not depend on the reward: the SNGNN-v2 episodes run without the weights.
        let config = crate::common::sngnn::without_sngnn_reward(config);
        let mut env = BatchEnv::new(config, EnvOptions::default()).unwrap();
        for step in ep.steps().filter(|s| s.replayable()) {
            env.set_state(0, &ep.document(step.state_after_motion()))
                .unwrap_or_else(|e| panic!("{name} step {}: {e}", step.t()));
            let expected = &step.v["info"]["interactions"];
            let list = |key: &str| -> Vec<[u32; 2]> {
                serde_json::from_value(expected[key].clone()).expect("index pairs")
            };
            let (hh, hl) = pairs(env.outputs(), 0);
            assert_eq!(hh, list("human-human"), "{name} step {}", step.t());
            assert_eq!(hl, list("human-laptop"), "{name} step {}", step.t());
            states += 1;
            with_pairs += usize::from(!hh.is_empty() || !hl.is_empty());
        }
    }
    println!("interactions equal on {states} golden states ({with_pairs} with pairs)");
    assert!(
        with_pairs > 1000,
        "too few states with interactions: {with_pairs}"
    );
}

/// Contract: under SAME_STEP autoreset the finishing step's interaction pairs are kept aside
/// with its observation.
#[test]
fn same_step_keeps_the_final_pairs() {
    let mut config = Config::from_name_or_path("exp2").unwrap();
    config.episode.length = 3;
    config.events.laptop_formation_probability = 0.0;
    let n = 8;
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs: n,
            seed: 3,
            autoreset: socnav::AutoresetMode::SameStep,
            ..Default::default()
        },
    )
    .unwrap();
    env.reset(None).unwrap();
    let before: Vec<_> = (0..n).map(|e| pairs(env.outputs(), e)).collect();
    let mut finished = 0;
    for _ in 0..5 {
        env.step(Actions::Continuous(&vec![0.0; 3 * n])).unwrap();
        let o = env.outputs();
        for e in (0..n).filter(|&e| o.has_final[e] != 0) {
            let (hh, hl) = (o.strides.hh(), o.strides.hl());
            assert_eq!(
                o.final_pair_count[2 * e..2 * e + 2],
                o.pair_count[2 * e..2 * e + 2]
            );
            assert_eq!(
                o.final_hh_pairs[e * hh..(e + 1) * hh],
                o.hh_pairs[e * hh..(e + 1) * hh]
            );
            assert_eq!(
                o.final_hl_pairs[e * hl..(e + 1) * hl],
                o.hl_pairs[e * hl..(e + 1) * hl]
            );
            // Experiment 2: a walker, then a moving and a standing group of 3 (records 1-3 and
            // 4-6), in every episode, before and after the reset.
            assert_eq!(pairs(o, e), before[e]);
            assert_eq!(o.final_pair_count[2 * e], 12);
            finished += 1;
        }
    }
    assert!(finished >= n, "every environment finishes within 5 steps");
}

// ---------------------------------------------------------------------------------------------
// Sensor noise (`NoisyObservations`)
// ---------------------------------------------------------------------------------------------

/// A batch of `config` with `n` environments, seed `seed`, reset.
fn batch(config: &Config, n: usize, seed: u64, threads: Option<usize>) -> BatchEnv {
    let mut env = BatchEnv::new(
        config.clone(),
        EnvOptions {
            n_envs: n,
            seed,
            threads,
            ..Default::default()
        },
    )
    .unwrap();
    env.reset(None).unwrap();
    env
}

/// A fixed action pattern (diff-drive) that depends only on (environment, step).
fn actions(n: usize, t: usize) -> Vec<f32> {
    (0..n)
        .flat_map(|k| {
            let forward = ((k * 7 + t * 3) % 11) as f32 / 5.0 - 1.0;
            let turn = ((k * 5 + t) % 9) as f32 / 4.0 - 1.0;
            [forward, 0.0, turn]
        })
        .collect()
}

/// Mean and standard deviation of a sample.
fn moments(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

/// Contract: the noise is an independent N(mean, std) sample per value, added to the robot's goal
/// x and y and to fields 6-13 of every present record of a noisy type; one-hot fields, the robot
/// radius, types without noise and (unpadded) the padding are untouched; the noise changes
/// neither the state nor the counts.
///
/// The noise is measured as the difference between a noisy batch and a clean one with the same
/// seed and actions (the observation never feeds back into the simulation); the f32 rounding of
/// that difference (≤ 1e-6 for values within 10) is negligible against the bounds.
#[test]
fn noise_statistics() {
    let mut clean = Config::from_name_or_path("exp2").unwrap();
    clean.events.laptop_formation_probability = 0.0;
    clean.events.laptop_dispersal_probability = 0.0;
    let mut noisy = clean.clone();
    let noise = &mut noisy.observation.noise;
    noise.robot.mean = 0.05;
    noise.robot.std = 0.2;
    noise.humans.mean = -0.1;
    noise.humans.std = 0.3;
    noise.tables.std = 0.5;
    noise.walls.mean = 0.2;
    noise.walls.std = 0.1;
    let (n, steps) = (64, 30);
    let mut a = batch(&clean, n, 9, None);
    let mut b = batch(&noisy, n, 9, None);
    let l = *a.layout();
    // Samples per noisy type: robot, humans, tables, walls.
    let mut samples: [Vec<f64>; 4] = Default::default();
    // Pairs (x noise, y noise) of the same record, for the independence check.
    let mut xy: (Vec<f64>, Vec<f64>) = Default::default();
    for t in 0..=steps {
        if t > 0 {
            a.step(Actions::Continuous(&actions(n, t))).unwrap();
            b.step(Actions::Continuous(&actions(n, t))).unwrap();
        }
        assert_eq!(
            a.state().unwrap().fingerprint(),
            b.state().unwrap().fingerprint(),
            "state"
        );
        assert_eq!(a.outputs().obs_count, b.outputs().obs_count, "counts");
        for e in 0..n {
            let (ra, rb) = (
                &a.outputs().obs[e * l.dim..(e + 1) * l.dim],
                &b.outputs().obs[e * l.dim..(e + 1) * l.dim],
            );
            let d = |i: usize| f64::from(rb[i]) - f64::from(ra[i]);
            for i in (0..6).chain([8]) {
                assert_eq!(ra[i], rb[i], "robot record index {i}");
            }
            samples[0].extend([d(6), d(7)]);
            for (t, slot) in [
                (entity::HUMANS, Some(1)),
                (entity::LAPTOPS, None),
                (entity::TABLES, Some(2)),
                (entity::WALLS, Some(3)),
            ] {
                for k in 0..l.capacity[t] {
                    let at = l.offset[t] + k * RECORD;
                    let present = k < counts(&a, e)[t] as usize;
                    for i in at..at + RECORD {
                        let noisy_field = present && i >= at + 6 && slot.is_some();
                        if let (true, Some(s)) = (noisy_field, slot) {
                            samples[s].push(d(i));
                        } else {
                            assert_eq!(ra[i], rb[i], "type {t} record {k} index {}", i - at);
                        }
                    }
                    if present && t == entity::WALLS {
                        xy.0.push(d(at + 6));
                        xy.1.push(d(at + 7));
                    }
                }
            }
        }
    }
    for (what, x, mean, std) in [
        ("robot", &samples[0], 0.05, 0.2),
        ("humans", &samples[1], -0.1, 0.3),
        ("tables", &samples[2], 0.0, 0.5),
        ("walls", &samples[3], 0.2, 0.1),
    ] {
        let (m, s) = moments(x);
        let n = x.len() as f64;
        println!("{what}: {n} samples, mean {m:.5} (expected {mean}), std {s:.5} (expected {std})");
        // 5 standard errors: the sample mean has standard error std/√n; the sample standard
        // deviation of a normal sample has relative standard error 1/√(2n).
        assert!(
            (m - mean).abs() <= 5.0 * std / n.sqrt(),
            "{what}: mean {m} of {n} samples, expected {mean} (std {std})"
        );
        assert!(
            (s / std - 1.0).abs() <= 5.0 / (2.0 * n).sqrt(),
            "{what}: standard deviation {s} of {n} samples, expected {std}"
        );
    }
    // Independent draws: the correlation of a record's x and y noise has standard error 1/√n.
    let n = xy.0.len() as f64;
    let (mx, sx) = moments(&xy.0);
    let (my, sy) = moments(&xy.1);
    let r =
        xy.0.iter()
            .zip(&xy.1)
            .map(|(x, y)| (x - mx) * (y - my))
            .sum::<f64>()
            / ((n - 1.0) * sx * sy);
    assert!(
        r.abs() <= 5.0 / n.sqrt(),
        "x/y noise correlation {r} over {n}"
    );
}

/// Contract (0.1.1 padded mode): the noise is added to every record of a type's capacity, the
/// all-zero padding included (its one-hot stays zero), and the counts still count real records.
#[test]
fn noise_on_padded_records() {
    let mut config = scene_config();
    config.observation.padded = true;
    config.observation.noise.humans.std = 0.1;
    let mut doc = scene(false, [0.0, 0.0, 0.0], [3.0, -3.0]);
    push(&mut doc, "humans", static_human(1, 2.0, 0.5, 0.0));
    let env = load(config, &[doc]);
    let l = *env.layout();
    assert_eq!(l.capacity[entity::WALLS], 0, "padded mode omits the walls");
    assert_eq!(counts(&env, 0)[entity::HUMANS], 1);
    for k in 1..l.capacity[entity::HUMANS] {
        let r = record(&env, 0, entity::HUMANS, k);
        assert!(r[..6].iter().all(|&x| x == 0.0), "one-hot of padding {k}");
        // |N(0, 0.1)| ≤ 0.6 (6 σ); exactly 0 only with probability 2^-24 per value.
        assert!(
            r[6..].iter().all(|&x| x != 0.0 && x.abs() <= 0.6),
            "padding record {k}: {r:?}"
        );
    }
    // The plants have no noise: their padding stays zero.
    assert!(
        (0..l.capacity[entity::PLANTS])
            .all(|k| record(&env, 0, entity::PLANTS, k).iter().all(|&x| x == 0.0))
    );
}

/// Contract: visibility is decided before the noise, on true positions: the counts with noise are
/// those without, and the padding of an unpadded observation stays zero.
#[test]
fn noise_after_visibility() {
    let mut config = Config::from_name_or_path("exp2").unwrap();
    config.observation.fov = 2.0;
    config.observation.range = Some(4.0);
    let mut noisy = config.clone();
    noisy.observation.noise.humans.std = 1.0;
    noisy.observation.noise.walls.std = 1.0;
    let n = 32;
    let mut a = batch(&config, n, 4, None);
    let mut b = batch(&noisy, n, 4, None);
    for t in 0..20 {
        a.step(Actions::Continuous(&actions(n, t))).unwrap();
        b.step(Actions::Continuous(&actions(n, t))).unwrap();
        assert_eq!(a.outputs().obs_count, b.outputs().obs_count, "step {t}");
        assert_eq!(a.outputs().pair_count, b.outputs().pair_count, "step {t}");
        for e in 0..n {
            assert_padding_zero(&b, e);
        }
    }
    let seen: u32 = a.outputs().obs_count.iter().sum();
    let all: u32 = batch(&Config::from_name_or_path("exp2").unwrap(), n, 4, None)
        .outputs()
        .obs_count
        .iter()
        .sum();
    assert!(
        seen > 0 && seen < all,
        "the view hides some records: {seen} of {all}"
    );
}

/// Contract (determinism): the noise is a function of (episode seed, tick, value):
/// the same seed gives the same noise whatever the thread count and the environment's index;
/// another seed or another step gives different noise.
#[test]
fn noise_is_deterministic() {
    let mut config = Config::from_name_or_path("exp2").unwrap();
    config.observation.frame = ObsFrame::World;
    config.observation.fov = 4.0;
    config.observation.noise.robot.std = 0.1;
    config.observation.noise.humans.std = 0.1;
    config.observation.noise.walls.std = 0.1;
    let n = 96;
    let mut one = batch(&config, n, 5, Some(1));
    let mut two = batch(&config, n, 5, Some(2));
    let mut other = batch(&config, n, 6, Some(2));
    for t in 0..10 {
        for env in [&mut one, &mut two, &mut other] {
            env.step(Actions::Continuous(&actions(n, t))).unwrap();
        }
        assert_eq!(one.outputs().obs, two.outputs().obs, "step {t}: threads");
        assert_eq!(one.outputs().hh_pairs, two.outputs().hh_pairs);
        assert_ne!(one.outputs().obs, other.outputs().obs, "step {t}: seeds");
    }
    // The noise belongs to the episode, not to the index: environment 0 loaded into 1 (its
    // episode seed included) gets the same noise; under another episode seed, other noise.
    let doc = one.get_state(0).unwrap();
    one.set_state(1, &doc).unwrap();
    let dim = one.layout().dim;
    let o = &one.outputs().obs;
    assert_eq!(
        o[..dim],
        o[dim..2 * dim],
        "environment 0's episode at index 1"
    );
    let mut reseeded = doc.clone();
    reseeded["socnav"]["seed"] = json!(doc["socnav"]["seed"].as_u64().unwrap() ^ 1);
    one.set_state(1, &reseeded).unwrap();
    let o = &one.outputs().obs;
    assert_ne!(o[..dim], o[dim..2 * dim], "another episode seed");
    // The same state at another tick gets different noise.
    let before = o[..dim].to_vec();
    let mut later = doc.clone();
    later["state"]["tick"] = json!(doc["state"]["tick"].as_u64().unwrap() + 1);
    one.set_state(0, &later).unwrap();
    assert_ne!(one.outputs().obs[..dim], before[..], "ticks");
    one.set_state(0, &doc).unwrap();
    assert_eq!(one.outputs().obs[..dim], before[..], "same key, same noise");
}

// ---------------------------------------------------------------------------------------------
// Configuration
// ---------------------------------------------------------------------------------------------

/// Contract (docs/spec.md, style rule 8): every new key is validated, each problem naming its key
/// and value.
#[test]
fn observation_keys_are_validated() {
    let text = r#"
        [observation]
        frame = "world"
        robot_velocity = true
        fov = 7.0
        range = 0.0
        noise.humans = { mean = nan, std = -0.1 }
        noise.walls = { std = inf }
    "#;
    let err = Config::from_toml_str(text).unwrap_err().to_string();
    for needle in [
        "`observation.fov` must lie in (0, 2π] rad, got 7",
        "`observation.range` must be a finite number > 0 m (omit the key for an unlimited range), got 0",
        "`observation.robot_velocity` applies to the robot frame only",
        "`observation.noise.humans.mean` must be finite, got NaN",
        "`observation.noise.humans.std` must be a finite number >= 0, got -0.1",
        "`observation.noise.walls.std` must be a finite number >= 0, got inf",
    ] {
        assert!(err.contains(needle), "missing `{needle}` in:\n{err}");
    }
    let err = Config::from_toml_str("[observation]\nfov = 0.0\nframe = \"map\"")
        .unwrap_err()
        .to_string();
    assert!(err.contains("frame"), "an unknown frame is refused: {err}");
    let ok = Config::from_toml_str(
        "[observation]\nfov = 1.5\nrange = 4.0\nnoise.robot = { mean = -0.2, std = 0.0 }",
    )
    .unwrap();
    assert_eq!(ok.observation.range, Some(4.0));
    assert!(ok.observation.noise.robot.is_on(), "a mean alone is noise");
}

// ---------------------------------------------------------------------------------------------
// The one-hot floats and the counts
// ---------------------------------------------------------------------------------------------

/// Contract: an entity record's one-hot floats follow from the per-type counts beside its row (1.0
/// at the type's place in the first `count` records of a type, 0.0 elsewhere and in padding), in
/// every shipped config and with every observation option, for `obs` and SAME_STEP's `final_obs`
/// alike: a row without them, rebuilt from its counts, is the row bit for bit. The GPU backend
/// keeps and reads back rows without them (src/backend/obs_payload.rs), so this is what makes its
/// observation the CPU's in configs and options its parity tests do not run.
#[test]
fn the_one_hot_floats_follow_from_the_counts() {
    use socnav::backend::obs_payload::{expand, strip_row};
    let mut configs = Vec::new();
    for name in common::config_names() {
        let c = common::load_config(&name);
        let mut padded = c.clone();
        padded.observation.padded = !c.observation.padded;
        let mut partial = c.clone();
        partial.observation.fov = 1.75;
        partial.observation.range = Some(4.0);
        let mut world = partial.clone();
        world.observation.frame = ObsFrame::World;
        let mut noisy = padded.clone();
        noisy.observation.noise.humans.std = 0.3;
        noisy.observation.noise.walls.mean = 0.2;
        noisy.observation.noise.plants.std = 0.1;
        configs.extend([c, padded, partial, world, noisy].map(|c| (name.clone(), c)));
    }
    let (n, steps) = (24, 40);
    let mut finals = 0;
    for (name, mut c) in configs {
        // Short episodes, so that SAME_STEP writes final observations.
        c.episode.length = 12;
        let mut env = BatchEnv::new(
            c,
            EnvOptions {
                n_envs: n,
                seed: 5,
                autoreset: socnav::AutoresetMode::SameStep,
                ..Default::default()
            },
        )
        .unwrap();
        env.reset(None).unwrap();
        let l = *env.layout();
        let mut payload = vec![0u32; l.payload_dim()];
        for t in 0..steps {
            env.step(Actions::Continuous(&actions(n, t))).unwrap();
            let o = env.outputs();
            for (rows, counts) in [(&o.obs, &o.obs_count), (&o.final_obs, &o.final_obs_count)] {
                let words: Vec<u32> = rows.iter().map(|v| v.to_bits()).collect();
                for e in 0..n {
                    let row = &words[e * l.dim..(e + 1) * l.dim];
                    strip_row(&l, row, &mut payload);
                    let mut rebuilt = vec![u32::MAX; l.dim];
                    expand(
                        &l,
                        0,
                        &payload,
                        &counts[5 * e..5 * e + 5],
                        &mut rebuilt,
                        None,
                    );
                    if let Some(k) = (0..l.dim).find(|&k| rebuilt[k] != row[k]) {
                        panic!(
                            "{name}, step {t}, env {e}: float {k} of the row is not its counts'"
                        );
                    }
                }
            }
            finals += o.has_final.iter().filter(|&&f| f != 0).count();
        }
    }
    assert!(finals > 0, "no final observation was written");
}
