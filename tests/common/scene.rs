//! Hand-written scenes as state documents (the format of `src/document.rs`), loaded with
//! `set_state`: an empty 10 m room with the robot and its goal, then entities pushed into its
//! lists.

use serde_json::{Value, json};
use socnav::{BatchEnv, Config, EnvOptions};

/// The four walls of a 10 m square room, as the generator builds them (docs/spec.md 3.3).
pub fn room_walls() -> Value {
    use std::f64::consts::{FRAC_PI_2, PI};
    json!([
        {"id": 100, "x": 4.9, "y": 0.0, "theta": -FRAC_PI_2, "length": 10.0},
        {"id": 101, "x": 0.0, "y": -4.9, "theta": -PI, "length": 10.0},
        {"id": 102, "x": -4.9, "y": 0.0, "theta": FRAC_PI_2, "length": 10.0},
        {"id": 103, "x": 0.0, "y": 4.9, "theta": 0.0, "length": 10.0},
    ])
}

/// A scene: a 10 m room (walls only if `walls`), the robot at (x, y, θ) with its goal, fixed
/// per-episode human parameters, a fresh episode at tick 0.
pub fn scene(walls: bool, robot: [f64; 3], goal: [f64; 2]) -> Value {
    let metrics = json!({
        "prev_goal_distance": (goal[0] - robot[0]).hypot(goal[1] - robot[1]), "failure_to_progress": 0,
        "stalled_time": 0.0, "path_length": 0.0, "v_min": "inf", "v_max": 0.0, "v_avg": 0.0, "prev_vel": [0.0, 0.0],
        "a_min": "inf", "a_max": 0.0, "a_avg": 0.0, "prev_a": [0.0, 0.0],
        "jerk_min": "inf", "jerk_max": 0.0, "jerk_avg": 0.0, "compliant_count": 0,
    });
    let reward_state = json!({
        "prev_distance": null,
        "info": {"DISCOMFORT_SNGNN": 0.0, "DISCOMFORT_DSRNN": 0.0, "distance_reward": 0.0, "alive_reward": 0.0,
                 "sngnn_reward": 0.0},
    });
    let robot_doc = json!({"x": robot[0], "y": robot[1], "theta": robot[2], "goal": goal, "vel": [0.0, 0.0, 0.0]});
    let shadow = json!({"x": robot[0], "y": robot[1], "theta": robot[2], "vel": [0.0, 0.0, 0.0], "path_length": 0.0});
    json!({
        "room": {"map_x": 10.0, "map_y": 10.0, "shape": "square"},
        "walls": if walls { room_walls() } else { json!([]) },
        "spawn_blockers": [],
        "human_params": {
            "orca_neighborDist": 1.44, "orca_timeHorizon": 5.0, "orca_timeHorizonObst": 5.0, "orca_maxSpeed": 0.2,
            "sfm_r0": 0.05, "sfm_gamma": 0.25, "sfm_n": 1.0, "sfm_n_prime": 1.0, "sfm_lambda": 1.0,
        },
        "state": {
            "tick": 0, "robot": robot_doc, "shadow_robot": shadow,
            "humans": [], "groups": [], "hl_interactions": [], "laptops": [], "tables": [], "plants": [],
            "metrics": metrics, "reward_state": reward_state,
        },
    })
}

/// A lone human that never moves (its goal is its position).
pub fn static_human(id: u32, x: f64, y: f64, theta: f64) -> Value {
    json!({"id": id, "x": x, "y": y, "theta": theta, "speed": 0.0, "goal": [x, y], "policy": "orca", "role": "static"})
}

/// A lone walking human with an ORCA policy.
pub fn walker(id: u32, x: f64, y: f64, theta: f64, speed: f64, goal: [f64; 2]) -> Value {
    json!({"id": id, "x": x, "y": y, "theta": theta, "speed": speed, "goal": goal, "policy": "orca", "role": "dynamic"})
}

/// Append `item` to the list `list` (`humans`, `laptops`, ...) of the document's state.
pub fn push(doc: &mut Value, list: &str, item: Value) {
    doc["state"][list].as_array_mut().unwrap().push(item);
}

/// A batch of `config` with one environment per scene, each loaded from its document.
pub fn load(config: Config, scenes: &[Value]) -> BatchEnv {
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs: scenes.len(),
            seed: 0,
            ..Default::default()
        },
    )
    .unwrap();
    env.reset(None).unwrap();
    for (e, doc) in scenes.iter().enumerate() {
        env.set_state(e, doc)
            .unwrap_or_else(|err| panic!("scene {e}: {err}"));
    }
    env
}

/// The observation-records scene (no room walls): the robot at (1, 2) facing +y with goal
/// (1, 5), last command 0.1 m/s and 0.2 rad/s; a static human at (2, 2) facing +x (the robot
/// behind it: gaze 0) and a walker at (0, 2) facing +x towards the robot (gaze 1) at 0.05 m/s;
/// a laptop at (1, 3), a table at (-2, 2) turned 0.3 rad, a plant at (1, 0); a 2.5 m wall along x
/// centred at (1, 6) (segments centred at x = 0.25, 1.25 and, the 0.5 m remainder, 2.0) and a 2 m
/// wall along y centred at (-3, -3) (left end (-3, -4): segments centred at y = -3.5 and -2.5).
/// Static humans take the first slots.
pub fn records_scene() -> Value {
    let half_pi = std::f64::consts::FRAC_PI_2;
    let mut doc = scene(false, [1.0, 2.0, half_pi], [1.0, 5.0]);
    doc["state"]["robot"]["vel"] = json!([0.1, 0.0, 0.2]);
    push(&mut doc, "humans", static_human(2, 2.0, 2.0, 0.0));
    push(
        &mut doc,
        "humans",
        walker(1, 0.0, 2.0, 0.0, 0.05, [-3.0, 2.0]),
    );
    push(
        &mut doc,
        "laptops",
        json!({"id": 3, "x": 1.0, "y": 3.0, "theta": 0.0}),
    );
    push(
        &mut doc,
        "tables",
        json!({"id": 4, "x": -2.0, "y": 2.0, "theta": 0.3}),
    );
    push(&mut doc, "plants", json!({"id": 5, "x": 1.0, "y": 0.0}));
    doc["walls"] = json!([
        {"id": 6, "x": 1.0, "y": 6.0, "theta": 0.0, "length": 2.5},
        {"id": 7, "x": -3.0, "y": -3.0, "theta": half_pi, "length": 2.0},
    ]);
    doc
}
