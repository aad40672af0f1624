//! The API boundary (docs/spec.md, style rules 7 and 8): `BatchEnv` rejects what a caller can get
//! wrong with a typed error whose message names the environment and the value, and a rejected call
//! changes nothing. And the state documents: `get_state` → `set_state` → `get_state` is exact,
//! and a loaded environment steps exactly as the original does.

use crate::common;

use common::valid_outputs;
use std::path::Path;

use serde_json::{Value, json};
use socnav::document::FORMAT;
use socnav::state::columns::FNV_OFFSET;
use socnav::{Actions, BatchEnv, Config, EnvOptions, SimError};

fn config(name: &str) -> Config {
    Config::from_file(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("configs")
            .join(format!("{name}.toml")),
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn make(config: Config, n_envs: usize, seed: u64) -> BatchEnv {
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs,
            seed,
            ..Default::default()
        },
    )
    .unwrap();
    env.reset(None).unwrap();
    env
}

/// Actions that depend on (env, step) only.
fn actions(n: usize, t: usize) -> Vec<f32> {
    (0..n)
        .flat_map(|k| {
            [
                ((k + 2 * t) % 5) as f32 / 2.0 - 1.0,
                0.0,
                ((k * 3 + t) % 7) as f32 / 3.0 - 1.0,
            ]
        })
        .collect()
}

/// Fingerprints of the state and of every output column.
fn fingerprints(env: &BatchEnv) -> (u64, u64) {
    let o = env.outputs();
    (
        env.state().unwrap().fingerprint(),
        (0..o.n_envs).fold(FNV_OFFSET, |h, e| o.fingerprint_env(e, h)),
    )
}

/// Step with invalid actions, expect `SimError::Action` whose message holds every needle, and
/// check that nothing changed.
fn rejected(env: &mut BatchEnv, actions: Actions<'_>, needles: &[&str]) {
    let before = fingerprints(env);
    let err = env
        .step(actions)
        .expect_err("invalid actions must be rejected");
    let SimError::Action { message: msg, .. } = &err else {
        panic!("expected SimError::Action, got {err:?}")
    };
    for needle in needles {
        assert!(
            msg.contains(needle),
            "message {msg:?} does not name {needle:?}"
        );
    }
    assert_eq!(
        fingerprints(env),
        before,
        "a rejected step changed the batch ({msg})"
    );
}

/// Contract: invalid continuous actions are rejected before anything moves, naming the
/// environment and the offending value.
#[test]
fn step_rejects_invalid_continuous_actions() {
    let n = 4;
    let mut env = make(config("exp1"), n, 0);
    env.step(Actions::Continuous(&actions(n, 0))).unwrap(); // mid-episode, not just after reset
    let good = actions(n, 1);
    rejected(&mut env, Actions::Continuous(&good[..11]), &["12", "11"]);
    rejected(
        &mut env,
        Actions::Continuous(&[good.clone(), vec![0.0; 3]].concat()),
        &["12", "15"],
    );
    let mut nan = good.clone();
    nan[3 * 2] = f32::NAN;
    rejected(
        &mut env,
        Actions::Continuous(&nan),
        &["environment 2", "NaN"],
    );
    let mut inf = good.clone();
    inf[3 * 3 + 2] = f32::NEG_INFINITY;
    rejected(
        &mut env,
        Actions::Continuous(&inf),
        &["environment 3", "inf"],
    );
    let mut lateral = good.clone();
    lateral[3 + 1] = 0.5;
    rejected(
        &mut env,
        Actions::Continuous(&lateral),
        &["environment 1", "0.5", "diff-drive"],
    );
    // The valid actions still step afterwards.
    env.step(Actions::Continuous(&good)).unwrap();
}

/// Contract: a holonomic robot accepts a lateral component (the diff-drive check is the only
/// reason to reject it).
#[test]
fn holonomic_robot_accepts_lateral_actions() {
    let mut c = config("exp1");
    c.robot.kinematics = socnav::config::Kinematics::Holonomic;
    let mut env = make(c, 2, 0);
    env.step(Actions::Continuous(&[0.0, 0.5, 0.0, 0.0, -1.0, 0.0]))
        .unwrap();
}

/// Contract: discrete actions must be one per environment and in 0..7.
#[test]
fn step_rejects_invalid_discrete_actions() {
    let mut env = make(config("exp1"), 4, 0);
    rejected(&mut env, Actions::Discrete(&[0, 1, 2]), &["4", "3"]);
    rejected(
        &mut env,
        Actions::Discrete(&[0, 1, 2, 7]),
        &["environment 3", "7"],
    );
    rejected(
        &mut env,
        Actions::Discrete(&[0, u32::MAX, 2, 3]),
        &["environment 1", &u32::MAX.to_string()],
    );
    env.step(Actions::Discrete(&[0, 1, 2, 6])).unwrap();
}

/// Contract: a batch needs environments and threads.
#[test]
fn options_are_validated() {
    let err = BatchEnv::new(
        config("exp1"),
        EnvOptions {
            n_envs: 0,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(&err, SimError::Shape { what: "n_envs", message: m } if m.contains("n_envs") && m.contains('0')),
        "{err:?}"
    );
    let err = BatchEnv::new(
        config("exp1"),
        EnvOptions {
            threads: Some(0),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(&err, SimError::Shape { what: "threads", message: m } if m.contains("threads") && m.contains('0')),
        "{err:?}"
    );
    // A count past the bound is refused before any thread starts (2^63 of them would hang).
    for threads in [socnav::MAX_THREADS + 1, 1 << 63] {
        let err = BatchEnv::new(
            config("exp1"),
            EnvOptions {
                threads: Some(threads),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(
            matches!(&err, SimError::Shape { what: "threads", message: m }
                if m.contains(&threads.to_string()) && m.contains("1..=1024")),
            "{err:?}"
        );
    }
}

/// Contract: a reset mask has one entry per environment; a wrong one changes nothing.
#[test]
fn reset_envs_rejects_a_wrong_mask() {
    let mut env = make(config("exp1"), 4, 0);
    env.step(Actions::Continuous(&actions(4, 0))).unwrap();
    let before = fingerprints(&env);
    let err = env.reset_envs(&[true, false, true]).unwrap_err();
    assert!(
        matches!(&err, SimError::Shape { what: "reset mask", message: m } if m.contains('3') && m.contains('4')),
        "{err:?}"
    );
    assert_eq!(fingerprints(&env), before);
}

/// Contract: environment indices are checked.
#[test]
fn state_documents_check_the_environment_index() {
    let mut env = make(config("exp1"), 3, 0);
    let err = env.get_state(3).unwrap_err();
    assert!(
        matches!(&err, SimError::EnvIndex { env: 3, n_envs: 3 }),
        "{err:?}"
    );
    let doc = env.get_state(0).unwrap();
    let err = env.set_state(3, &doc).unwrap_err();
    assert!(
        matches!(&err, SimError::EnvIndex { env: 3, n_envs: 3 }),
        "{err:?}"
    );
}

/// `doc` with the value at a `/`-separated path removed.
fn without(doc: &Value, path: &str) -> Value {
    let mut doc = doc.clone();
    let (parent, key) = path.rsplit_once('/').unwrap();
    let target = doc
        .pointer_mut(parent)
        .unwrap_or_else(|| panic!("no {parent}"));
    match target {
        Value::Object(m) => assert!(m.remove(key).is_some(), "no {path}"),
        other => panic!("{parent} is {other}"),
    }
    doc
}

/// Load `doc` into environment 0, expect a `SimError::Shape` holding every needle, and check
/// that the environment is unchanged by the failed load.
fn load_rejected(env: &mut BatchEnv, doc: &Value, needles: &[&str]) -> String {
    let before = (
        env.state().unwrap().fingerprint_env(0, FNV_OFFSET),
        env.get_state(0).unwrap(),
    );
    let err = env
        .set_state(0, doc)
        .expect_err("the document must be rejected");
    let SimError::Shape {
        what: "state document",
        message: msg,
    } = &err
    else {
        panic!("expected SimError::Shape, got {err:?}")
    };
    for needle in needles {
        assert!(
            msg.contains(needle),
            "message {msg:?} does not name {needle:?}"
        );
    }
    let after = (
        env.state().unwrap().fingerprint_env(0, FNV_OFFSET),
        env.get_state(0).unwrap(),
    );
    assert!(
        after == before,
        "a rejected set_state changed environment 0 ({msg})"
    );
    msg.clone()
}

/// exp2 with four tables and no laptop, and a state document of environment 0 whose tables lie
/// across each other at the room's centre, a star of four: RVO2 splits their edges (and the
/// walls') where the others' edge lines cross them, to 94 processed obstacle vertices where the
/// config holds 8 a polygon (72 with the walls and the standing group). Generated scenes never
/// overlap so (`whole_step::scenario_props`).
pub(crate) fn overlapping_tables(backend: socnav::backend::BackendChoice) -> (BatchEnv, Value) {
    let mut c = config("exp2");
    c.counts.tables = [4, 4];
    c.counts.laptops = [0, 0];
    let mut env = BatchEnv::new(
        c,
        EnvOptions {
            n_envs: 2,
            seed: 0,
            backend,
            ..Default::default()
        },
    )
    .expect("a batch");
    env.reset(None).unwrap();
    let mut doc = env.get_state(0).unwrap();
    let tables = doc["state"]["tables"].as_array_mut().expect("tables");
    assert_eq!(tables.len(), 4);
    for (k, t) in tables.iter_mut().enumerate() {
        t["x"] = json!(0.0);
        t["y"] = json!(0.0);
        t["theta"] = json!(0.1 + k as f64 * std::f64::consts::FRAC_PI_4);
    }
    (env, doc)
}

/// Contract: a document whose obstacles need more processed ORCA vertices than the config holds
/// (tables loaded across each other) is rejected with both numbers, not a panic, and the
/// environment stays as it was and steps on.
#[test]
fn set_state_rejects_obstacles_beyond_the_capacity() {
    let (mut env, doc) = overlapping_tables(socnav::backend::BackendChoice::Cpu);
    let cap = env.state().unwrap().strides.obstacle_vertices;
    let msg = load_rejected(
        &mut env,
        &doc,
        &[
            "environment 0",
            "ORCA obstacles need",
            &format!("more than the {cap} this config holds"),
            "move them apart",
        ],
    );
    let needed: usize = msg
        .split("need ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no count in {msg:?}"));
    assert!(needed > cap, "{msg}");
    println!("{msg}");
    env.step(Actions::Discrete(&[2, 2])).unwrap();
    assert!(env.outputs().obs.iter().all(|v| v.is_finite()));
}

/// Contract: a group with more members than the config's group size is refused by capacity
/// (its pairs would overrun the observation's pair rows: a panic before), and the environment
/// stays as it was.
#[test]
fn set_state_refuses_a_group_larger_than_the_group_size() {
    let source = make(config("exp2"), 1, 0);
    let doc = source.get_state(0).unwrap();
    let largest = doc["state"]["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g["members"].as_array().unwrap().len())
        .max()
        .unwrap();
    assert!(largest >= 3, "exp2 has groups of 3");
    // The same scene's capacities but for the group size: the members count as walkers.
    let mut smaller = config("exp2");
    smaller.counts.group_size = [2, 2];
    smaller.counts.dynamic_humans[1] += 4;
    let mut env = make(smaller, 1, 0);
    load_rejected(
        &mut env,
        &doc,
        &[
            &format!("{largest} members of a group"),
            "capacity is 2",
            "counts.group_size",
        ],
    );
}

/// Contract: a formation in a document must be one the step can finish: every slot of a forming
/// crowd has one walker, and a walker on its way to a laptop has a laptop-user slot to take (the
/// step asserted both). ORCA's time horizons are at least the 0.1 s a reset draws (RVO2
/// divides by them).
#[test]
fn set_state_refuses_formations_the_step_cannot_finish() {
    // exp3 forms crowds (a group slot is free for one); exp1 seats no laptop user.
    let mut env = make(config("exp3"), 1, 0);
    let doc = env.get_state(0).unwrap();
    let id = doc["state"]["humans"][0]["id"].clone();
    let crowd = |slots: Value, slot_of: Value| {
        let mut d = doc.clone();
        d["state"]["crowd_forming"] = json!({"slots": slots, "slot_of": slot_of,
            "centre": [0.0, 0.0], "almost_formed_count": 0});
        d
    };
    let two_slots = json!([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
    let key = id.to_string();
    for (d, needles) in [
        (
            crowd(two_slots.clone(), json!({ key.as_str(): 0 })),
            &["state.crowd_forming.slot_of", "names 1 walkers for 2 slots"][..],
        ),
        (
            crowd(json!([]), json!({})),
            &["state.crowd_forming.slots", "at least one slot"],
        ),
    ] {
        load_rejected(&mut env, &d, needles);
    }
    let mut env = make(config("exp1"), 1, 0);
    let doc = env.get_state(0).unwrap();
    let mut d = doc.clone();
    d["state"]["hl_forming"] =
        json!({"human": doc["state"]["humans"][0]["id"], "laptop": 1, "seat": [0.0, 0.0, 0.0]});
    load_rejected(
        &mut env,
        &d,
        &[
            "state.hl_forming",
            "the 0 laptop users already fill the config's capacity",
        ],
    );
    for key in ["orca_timeHorizon", "orca_timeHorizonObst"] {
        let mut d = doc.clone();
        d["human_params"][key] = json!(0.0);
        load_rejected(
            &mut env,
            &d,
            &[&format!("human_params.{key}"), "[0.1, 1000000000]"],
        );
    }
}

/// Contract: a wall too long to count its observed segments in a u32 counts as u32::MAX (which
/// any capacity refuses), not as a count wrapped to 0 (which every capacity passes).
#[test]
fn a_wall_of_more_segments_than_a_u32_holds_saturates() {
    assert_eq!(socnav::room::segment_count(1e9, 0.1), u32::MAX);
    assert_eq!(socnav::room::segment_count(2.5, 1.0), 3);
    assert_eq!(socnav::room::segment_count(2.0, 1.0), 2);
}

/// Contract: a state is copied only between batches of one config: another config's constants
/// (a human's size, say) would not be the ones its derived columns were made with.
#[test]
fn copy_state_from_refuses_a_batch_of_another_config() {
    let mut env = make(config("exp1"), 2, 0);
    let mut other_config = config("exp1");
    other_config.human.diameter *= 1.1;
    let other = make(other_config, 2, 0);
    let err = env.copy_state_from(&other).unwrap_err();
    assert!(
        matches!(&err, SimError::Shape { what: "state", message } if message.contains("another config")),
        "{err:?}"
    );
    env.copy_state_from(&make(config("exp1"), 2, 7)).unwrap();
}

/// Contract: a document missing a key is rejected with the path of the key.
#[test]
fn set_state_names_the_path_of_a_missing_key() {
    let mut env = make(config("exp2"), 2, 0);
    let doc = env.get_state(1).unwrap();
    for (pointer, path) in [
        ("/state/robot/x", "state.robot.x"),
        ("/human_params/sfm_r0", "human_params.sfm_r0"),
        ("/state/humans/0/x", "state.humans[0].x"),
        ("/state/metrics/v_min", "state.metrics.v_min"),
        ("/room/map_x", "room.map_x"),
    ] {
        let msg = load_rejected(&mut env, &without(&doc, pointer), &[path, "missing"]);
        println!("{path}: {msg}");
    }
    // A value of the wrong type names its path too.
    let mut bad = doc.clone();
    bad["state"]["tables"][0]["theta"] = json!("north");
    load_rejected(&mut env, &bad, &["state.tables[0].theta", "north"]);
}

/// Contract: a document larger than the batch's capacities names the capacity.
#[test]
fn set_state_names_an_exceeded_capacity() {
    let mut env = make(config("exp1"), 1, 0); // capacity: 1 human
    let mut doc = env.get_state(0).unwrap();
    let mut second = doc["state"]["humans"][0].clone();
    second["id"] = json!(99);
    second["x"] = json!(-3.0);
    doc["state"]["humans"].as_array_mut().unwrap().push(second);
    let msg = load_rejected(&mut env, &doc, &["2 humans", "capacity is 1"]);
    println!("{msg}");
}

/// Contract: a document's entities must lie in its room and its numbers be finite, as a step
/// keeps them: a plant 1000 km out collapses its obstacle square in 32-bit coordinates (ORCA's
/// obstacle processing would panic on the zero-length edge), a robot at NaN poisons every output.
#[test]
fn set_state_refuses_entities_outside_the_room_or_not_finite() {
    let mut env = make(config("exp1"), 1, 0);
    let doc = env.get_state(0).unwrap();
    let mut far = doc.clone();
    far["state"]["plants"][0]["x"] = json!(1.0e6);
    load_rejected(&mut env, &far, &["plant slot 0", "outside the room"]);
    let mut nan = doc.clone();
    nan["state"]["robot"]["x"] = json!("nan");
    load_rejected(
        &mut env,
        &nan,
        &["`state.robot.x` is NaN", "must be finite"],
    );
    // The batch is untouched and steps on.
    env.step(Actions::Continuous(&actions(1, 0))).unwrap();
    assert!(env.outputs().obs.iter().all(|v| v.is_finite()));
}

/// Contract: sizes that are config constants in socnav must match the batch's config, and the
/// message gives both values.
#[test]
fn set_state_names_a_radius_that_differs_from_the_config() {
    let mut env = make(config("exp1"), 1, 0);
    let mut doc = env.get_state(0).unwrap();
    doc["state"]["robot"]["radius"] = json!(0.7);
    let msg = load_rejected(
        &mut env,
        &doc,
        &["state.robot.radius", "0.7", "0.25", "robot.radius"],
    );
    println!("{msg}");
}

/// Contract: a document is a JSON object, and one that names its format names socnav's (a
/// golden snapshot names none); the message says what was found.
#[test]
fn set_state_refuses_what_is_not_a_socnav_document() {
    let mut env = make(config("exp1"), 1, 0);
    for (doc, needles) in [
        (json!(null), &["must be a JSON object", "null"][..]),
        (json!([1, 2]), &["must be a JSON object", "a list"]),
        (json!("{}"), &["must be a JSON object", "a string"]),
    ] {
        load_rejected(&mut env, &doc, needles);
    }
    let mut doc = env.get_state(0).unwrap();
    doc["format"] = json!("socnav-state/0");
    load_rejected(&mut env, &doc, &["`format`", "socnav-state/0", FORMAT]);
    doc["format"] = json!(1);
    load_rejected(&mut env, &doc, &["`format` is 1"]);
    // Without a format (a golden episode's snapshot) the same document loads.
    doc.as_object_mut().unwrap().remove("format");
    env.set_state(0, &doc).unwrap();
}

/// Contract: `get_state` → `set_state` → `get_state` gives the same JSON, exactly, for several
/// environments of every shipped config (mid-episode, after autoresets), both into the same
/// environment and into another batch.
#[test]
fn state_documents_round_trip_exactly() {
    let mut checked = 0;
    for name in common::config_names() {
        let mut c = config(&name);
        c.episode.length = 12; // autoresets inside the run
        let n = 8;
        let mut env = make(c.clone(), n, 3);
        for t in 0..20 {
            env.step(Actions::Continuous(&actions(n, t))).unwrap();
        }
        let mut other = make(c, n, 99);
        for k in 0..n {
            let doc = env.get_state(k).unwrap();
            env.set_state(k, &doc)
                .unwrap_or_else(|e| panic!("{name} env {k}: {e}"));
            assert_eq!(
                env.get_state(k).unwrap(),
                doc,
                "{name} env {k}: round trip in place"
            );
            let j = n - 1 - k;
            other
                .set_state(j, &doc)
                .unwrap_or_else(|e| panic!("{name} env {k} into env {j}: {e}"));
            assert_eq!(
                other.get_state(j).unwrap(),
                doc,
                "{name} env {k}: round trip into another batch"
            );
            checked += 1;
        }
    }
    assert!(checked >= 5 * 8, "only {checked} documents checked");
}

/// Contract: a loaded state steps exactly as the original. Every environment of a batch that has
/// run (with autoresets) is loaded into a fresh batch of the same seed; both then take the same
/// actions and must have the same documents, outputs and whole-state fingerprint (unused slots
/// included: they hold zeros, module docs of `socnav::state`) after every step.
#[test]
fn a_loaded_state_steps_identically() {
    for name in common::config_names() {
        let mut c = config(&name);
        c.episode.length = 15;
        let n = 8;
        let mut original = make(c.clone(), n, 21);
        for t in 0..25 {
            original.step(Actions::Continuous(&actions(n, t))).unwrap();
        }
        let mut loaded = make(c, n, 21);
        for k in 0..n {
            loaded
                .set_state(k, &original.get_state(k).unwrap())
                .unwrap();
        }
        for t in 25..60 {
            let a = actions(n, t);
            original.step(Actions::Continuous(&a)).unwrap();
            loaded.step(Actions::Continuous(&a)).unwrap();
            for k in 0..n {
                assert_eq!(
                    original.get_state(k).unwrap(),
                    loaded.get_state(k).unwrap(),
                    "{name} env {k}: documents after step {t}"
                );
            }
            assert!(
                valid_outputs(original.outputs()) == valid_outputs(loaded.outputs()),
                "{name}: outputs after step {t}"
            );
            assert_eq!(
                original
                    .state()
                    .unwrap()
                    .differing_columns(loaded.state().unwrap()),
                Vec::<&str>::new(),
                "{name}: state columns after step {t}"
            );
        }
    }
}

/// Contract: a batch too large for the machine is refused with `SimError::OutOfMemory` naming
/// its size before anything is allocated (an allocation failure would abort the process, a
/// Python interpreter with it), and a batch that fits is still made.
#[test]
fn a_batch_too_large_for_the_machine_is_refused_before_allocating() {
    for n_envs in [1usize << 40, 1 << 63, usize::MAX] {
        let options = EnvOptions {
            n_envs,
            ..Default::default()
        };
        match BatchEnv::new(config("exp1"), options) {
            Err(SimError::OutOfMemory {
                bytes,
                device,
                message,
            }) => {
                assert!(bytes > 1 << 40, "{bytes}");
                assert_eq!(device, None, "the host refused it");
                assert!(
                    message.contains(&format!("a batch of {n_envs} environments needs about"))
                        && message.contains("use fewer environments"),
                    "{message}"
                );
            }
            Err(other) => panic!("{n_envs}: expected OutOfMemory, got {other:?}"),
            Ok(_) => panic!("{n_envs} environments were made"),
        }
    }
    make(config("exp1"), 4, 0);
}

/// Contract (`BatchEnv::set_step_outputs`): the choice is kept, and on the CPU backend, which
/// writes its outputs in place, a lean batch steps to the same state and the same outputs, every
/// column included, as one that delivers everything.
#[test]
fn step_outputs_change_nothing_on_the_cpu() {
    use socnav::outputs::StepOutputs;
    let mut all = make(config("exp2"), 8, 5);
    let mut lean = make(config("exp2"), 8, 5);
    assert_eq!(all.step_outputs(), StepOutputs::ALL);
    lean.set_step_outputs(StepOutputs::LEAN);
    assert_eq!(lean.step_outputs(), StepOutputs::LEAN);
    for t in 0..30 {
        let a = actions(8, t);
        all.step(Actions::Continuous(&a)).unwrap();
        lean.step(Actions::Continuous(&a)).unwrap();
        assert_eq!(fingerprints(&all), fingerprints(&lean), "step {t}");
    }
}
