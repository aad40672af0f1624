//! `[model] contact_shape = "polygon64"`: contacts decided as 0.1.1 decides them, with discs as
//! shapely's 64-gons (docs/fidelity.md).
//!
//! - The option reaches `StepParams` and, with it, the three step-time contact decisions: the
//!   robot's collision (termination), the shadow robot's, and the human push-out (contacts), each
//!   on hand-made scenes whose contacts lie inside the 64-gon's inset.

mod common;

use std::f64::consts::PI;

use common::scene::{load, push, scene, static_human};
use serde_json::json;
use socnav::config::ContactShape;
use socnav::geometry::contact_shape;
use socnav::outputs::Outputs;
use socnav::pipeline::{Batch, STAGES};
use socnav::spec::{N_INFO, info};
use socnav::state::BatchState;
use socnav::{BatchEnv, Config};

// ---------------------------------------------------------------------------------------------
// The option
// ---------------------------------------------------------------------------------------------

/// Contract: the default is exact; `contact_shape = "polygon64"` reaches `StepParams`.
#[test]
fn the_option_reaches_the_step_params() {
    let exp1 = Config::from_name_or_path("exp1").unwrap();
    assert_eq!(exp1.model.contact_shape, ContactShape::Exact);
    let p = socnav::StepParams::new(&exp1, 0, Default::default());
    assert_eq!(p.contact_shape, contact_shape::EXACT);
    let c = Config::from_toml_str("[model]\ncontact_shape = \"polygon64\"\n").unwrap();
    assert_eq!(c.model.contact_shape, ContactShape::Polygon64);
    let p = socnav::StepParams::new(&c, 0, Default::default());
    assert_eq!(p.contact_shape, contact_shape::POLYGON64);
    // Serialised under its name, and read back.
    assert!(c.to_toml_string().contains("contact_shape = \"polygon64\""));
}

// ---------------------------------------------------------------------------------------------
// The three decisions on hand-made scenes
// ---------------------------------------------------------------------------------------------

/// Experiment 1 (robot r 0.25 m, humans r 0.36 m, plants r 0.4 m, tables 3 x 1.5 m, walls
/// 0.2 m thick) with room for the scenes below, contacts shaped as `shape`.
fn scene_config(shape: ContactShape) -> Config {
    let mut c = Config::from_name_or_path("exp1").unwrap();
    c.counts.static_humans = [0, 1];
    c.counts.dynamic_humans = [0, 1];
    c.counts.plants = [0, 1];
    c.counts.tables = [0, 1];
    c.model.contact_shape = shape;
    c
}

/// Where a centre at `dist` (m) from (x, y) along `angle` (rad) lies.
fn at(x: f64, y: f64, angle: f64, dist: f64) -> (f64, f64) {
    (x + dist * angle.cos(), y + dist * angle.sin())
}

/// Between two 64-gon vertices (the edge's normal), and along a vertex.
const BETWEEN: f64 = PI / 64.0;
const VERTEX: f64 = 0.0;
/// A contact distance's fraction inside the 64-gon's inset, (cos(π/64), 1) = (0.998795, 1).
const INSET: f64 = 0.9994;

/// Run `begin_step` (which marks the environments as stepping) then stage `stage` alone over
/// every environment of `env`'s state (the other stages would move the entities of the scene);
/// the state and outputs after them.
fn run_stage(env: &BatchEnv, stage: &str) -> (BatchState, Outputs) {
    let mut state = env.state().clone();
    let mut outputs = env.outputs().clone();
    let n_envs = state.n_envs;
    let mut b = Batch {
        s: state.chunk(),
        o: outputs.chunk(),
        actions: &[],
        sngnn: None,
        error: None,
    };
    for name in ["begin_step", stage] {
        let run = STAGES.iter().find(|s| s.name == name).unwrap().run;
        for e in 0..n_envs {
            run(env.params(), &mut b, e);
        }
    }
    assert!(b.error.is_none(), "{stage}: {:?}", b.error);
    (state, outputs)
}

/// The robot (and its shadow, which starts where it is) at the origin, goal far away, facing one
/// thing at a contact distance of `INSET` x the radii sum along `angle`: a static human, a
/// plant, or a table turned by `angle` with the robot beyond its +x face.
fn robot_scenes() -> Vec<(&'static str, f64, serde_json::Value)> {
    let mut out = Vec::new();
    for angle in [BETWEEN, VERTEX] {
        let mut human = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
        let (x, y) = at(0.0, 0.0, angle, (0.25 + 0.36) * INSET);
        push(&mut human, "humans", static_human(1, x, y, 0.0));
        out.push(("human", angle, human));
        let mut plant = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
        let (x, y) = at(0.0, 0.0, angle, (0.25 + 0.4) * INSET);
        push(&mut plant, "plants", json!({"id": 2, "x": x, "y": y}));
        out.push(("plant", angle, plant));
        // The table's centre 1.5 m (its half length) + the gap beyond the robot, along `angle`.
        let mut table = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
        let (x, y) = at(0.0, 0.0, angle, 1.5 + 0.25 * INSET);
        push(
            &mut table,
            "tables",
            json!({"id": 3, "x": x, "y": y, "theta": angle}),
        );
        out.push(("table", angle, table));
    }
    out
}

/// Contract: the robot's collision (termination) and the shadow robot's are decided with the
/// option's shapes: inside the inset, between vertices, only exact discs touch; along a vertex
/// both do.
#[test]
fn robot_and_shadow_collisions_follow_the_option() {
    let scenes = robot_scenes();
    let docs: Vec<_> = scenes.iter().map(|s| s.2.clone()).collect();
    for shape in [ContactShape::Exact, ContactShape::Polygon64] {
        let env = load(scene_config(shape), &docs);
        let (state, outputs) = run_stage(&env, "termination");
        for (e, (what, angle, _)) in scenes.iter().enumerate() {
            let expected = shape == ContactShape::Exact || *angle == VERTEX;
            let flag = |k: usize| outputs.info[e * N_INFO + k] == 1.0;
            let key = if *what == "human" {
                info::COLLISION_HUMAN
            } else {
                info::COLLISION_OBJECT
            };
            assert_eq!(
                (flag(info::COLLISION), flag(key)),
                (expected, expected),
                "{shape:?}: robot and {what} at angle {angle}"
            );
            assert_eq!(
                state.shadow_collided[e] == 1,
                expected,
                "{shape:?}: shadow robot and {what} at angle {angle}"
            );
        }
    }
}

/// Contract: a walker resting against a plant, a table or a wall inside the inset is pushed out
/// with exact discs; with 64-gons only where a vertex faces the object.
#[test]
fn human_push_out_follows_the_option() {
    let mut docs = Vec::new();
    let mut cases = Vec::new();
    for angle in [BETWEEN, VERTEX] {
        // A walker at (0, 0); its goal far away.
        let walker = |doc: &mut serde_json::Value| {
            push(
                doc,
                "humans",
                json!({"id": 1, "x": 0.0, "y": 0.0, "theta": 0.0, "speed": 0.0,
                       "goal": [-3.0, -3.0], "policy": "orca", "role": "dynamic"}),
            );
        };
        let mut plant = scene(false, [3.0, 3.0, 0.0], [3.0, -3.0]);
        walker(&mut plant);
        let (x, y) = at(0.0, 0.0, angle, (0.36 + 0.4) * INSET);
        push(&mut plant, "plants", json!({"id": 2, "x": x, "y": y}));
        docs.push(plant);
        cases.push(("plant", angle));
        let mut table = scene(false, [3.0, 3.0, 0.0], [3.0, -3.0]);
        walker(&mut table);
        let (x, y) = at(0.0, 0.0, angle, 1.5 + 0.36 * INSET);
        push(
            &mut table,
            "tables",
            json!({"id": 3, "x": x, "y": y, "theta": angle}),
        );
        docs.push(table);
        cases.push(("table", angle));
        // A 4 m wall turned by `angle` + π/2 (its face normal along `angle`), 0.2 m thick.
        let mut wall = scene(false, [3.0, 3.0, 0.0], [3.0, -3.0]);
        walker(&mut wall);
        let (x, y) = at(0.0, 0.0, angle, 0.1 + 0.36 * INSET);
        wall["walls"] =
            json!([{"id": 100, "x": x, "y": y, "theta": angle + PI / 2.0, "length": 4.0}]);
        docs.push(wall);
        cases.push(("wall", angle));
    }
    for shape in [ContactShape::Exact, ContactShape::Polygon64] {
        let env = load(scene_config(shape), &docs);
        let before = env.state().clone();
        let (after, _) = run_stage(&env, "contacts");
        for (e, (what, angle)) in cases.iter().enumerate() {
            let i = e * after.strides.humans;
            let pushed = (after.h_x[i], after.h_y[i]) != (before.h_x[i], before.h_y[i]);
            let expected = shape == ContactShape::Exact || *angle == VERTEX;
            assert_eq!(
                pushed, expected,
                "{shape:?}: human against a {what} at angle {angle}"
            );
        }
    }
}
