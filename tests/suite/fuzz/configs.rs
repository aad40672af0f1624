//! Configs drawn inside and just outside every bound: experiment 3's config (every key) with some
//! values replaced (scaled, negated, zeroed, huge, non-finite, swapped ranges, unknown enum
//! values, keys dropped or unknown keys added). Each must be refused with `SimError::Config`
//! listing its problems, or load; a config that loads must build a batch (or fail to place its
//! scenario with `SimError::Scenario`), reset, and step with extreme actions keeping every output
//! finite (the info fields documented as NaN excepted) and the state's invariants.

use proptest::prelude::*;
use socnav::{Actions, AutoresetMode, Config, SimError};
use toml::Value;

use super::assert_clean;

/// Every leaf of exp3's config as (section, key).
fn leaves(base: &toml::Table) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (section, table) in base {
        if let Some(t) = table.as_table() {
            for key in t.keys() {
                out.push((section.clone(), key.clone()));
            }
        }
    }
    out
}

/// A new value for `old` by mutation `kind` with the random number `x` in [0, 1).
fn mutate(old: &Value, kind: u8, x: f64) -> Option<Value> {
    let scale = [0.0, 0.01, 0.5, 2.0, 10.0, 1e6, -1.0, f64::NAN][usize::from(kind % 8)];
    Some(match old {
        Value::Float(f) => Value::Float(if kind % 11 == 10 {
            f64::INFINITY
        } else {
            f * scale + x * 1e-3
        }),
        Value::Integer(i) => Value::Integer(match kind % 5 {
            0 => 0,
            1 => -1,
            2 => i.saturating_mul(3),
            3 => (x * 50.0) as i64,
            _ => i64::MAX,
        }),
        Value::Array(a) if a.len() == 2 => {
            let lo = (x * 12.0) as i64;
            let hi = match kind % 4 {
                0 => lo - 1, // swapped range
                1 => lo,
                _ => lo + i64::from(kind % 6),
            };
            let as_float = a.iter().any(Value::is_float);
            if as_float {
                Value::Array(vec![
                    Value::Float(lo as f64 * scale.abs().min(3.0)),
                    Value::Float(hi as f64),
                ])
            } else {
                Value::Array(vec![Value::Integer(lo), Value::Integer(hi)])
            }
        }
        Value::Boolean(b) => Value::Boolean(!b),
        Value::String(s) => {
            let options = [
                "square",
                "rectangle",
                "L",
                "random",
                "orca",
                "sfm",
                "dsrnn",
                "sngnn",
                "holonomic",
                "diff-drive",
                "",
            ];
            Value::String(if kind.is_multiple_of(3) {
                format!("{s}-bogus")
            } else {
                options[(x * options.len() as f64) as usize].to_owned()
            })
        }
        _ => return None,
    })
}

/// What a mutated TOML config must do (see the module docs).
fn check(text: &str) {
    loaded_or_refused(Config::from_toml_str(text), text);
}

/// A loaded config runs cleanly; a refused one is refused with `SimError::Config` listing its
/// problems. `context` (the config's text) names the case in a failure.
fn loaded_or_refused(loaded: Result<Config, SimError>, context: &str) {
    match loaded {
        Ok(config) => run_cleanly(config, context),
        Err(SimError::Config(problems)) => {
            assert!(!problems.is_empty(), "a refusal lists its problems");
        }
        Err(e) => panic!("a config is refused with SimError::Config, got {e:?}\n{context}"),
    }
}

/// A config that loaded builds a batch (or fails to place its scenario with
/// `SimError::Scenario`), resets, and steps with extreme actions keeping its outputs clean.
fn run_cleanly(config: Config, context: &str) {
    let mut env = match super::batch(config, 3, 5, AutoresetMode::SameStep, 1) {
        Ok(env) => env,
        Err(SimError::Scenario { .. } | SimError::Sngnn(_)) => return,
        Err(e) => panic!("a valid config builds a batch and resets, got {e:?}\n{context}"),
    };
    let holonomic = env.params().holonomic != 0;
    let lateral = if holonomic { 1.0 } else { 0.0 };
    for t in 0..12 {
        let a = if t % 2 == 0 {
            [1.0, lateral, -1.0]
        } else {
            [-1.0, -lateral, 1.0]
        };
        let actions: Vec<f32> = (0..3).flat_map(|_| a).collect();
        match env.step(Actions::Continuous(&actions)) {
            Ok(()) => {}
            Err(SimError::Scenario { .. }) => return, // an autoreset could not place the next scenario
            Err(e) => panic!("step {t}: {e:?}\n{context}"),
        }
        assert_clean(&env, &format!("step {t}\n{context}"));
    }
}

fn base() -> toml::Table {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/exp3.toml")).unwrap();
    text.parse().unwrap()
}

proptest! {
    #![proptest_config(super::config(48))]

    #[test]
    fn mutated_configs_are_refused_clearly_or_run_cleanly(
        edits in prop::collection::vec((0usize..1000, 0u8..64, 0.0f64..1.0), 1..6),
        drop in prop::option::of(0usize..1000),
        unknown in any::<bool>(),
    ) {
        let mut doc = base();
        let keys = leaves(&doc);
        for (pick, kind, x) in edits {
            let (section, key) = &keys[pick % keys.len()];
            let table = doc[section.as_str()].as_table_mut().unwrap();
            if let Some(new) = mutate(&table[key.as_str()], kind, x) {
                table.insert(key.clone(), new);
            }
        }
        if let Some(pick) = drop {
            let (section, key) = &keys[pick % keys.len()];
            doc[section.as_str()].as_table_mut().unwrap().remove(key.as_str());
        }
        if unknown {
            doc["room"].as_table_mut().unwrap().insert("sise_x".into(), Value::Integer(3));
        }
        check(&toml::to_string(&doc).unwrap());
    }
}

/// Found by this target: `human.max_speed` 1e5 m/s (exp3 with the speed scaled by 1e6) flew a
/// walker 58 km out of the room in one step. Such a speed is refused now: a step may move an agent
/// at most its diameter.
#[test]
fn regression_a_walker_faster_than_its_diameter_a_step_is_refused() {
    let mut doc = base();
    doc["human"]
        .as_table_mut()
        .unwrap()
        .insert("max_speed".into(), Value::Float(100000.0));
    let err = Config::from_toml_str(&toml::to_string(&doc).unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`human.max_speed` 100000 m/s")
            && err.contains("more than its diameter (0.72 m)"),
        "{err}"
    );
    doc["human"]
        .as_table_mut()
        .unwrap()
        .insert("max_speed".into(), Value::Float(0.7));
    check(&toml::to_string(&doc).unwrap());
}

/// The unmutated config passes the same check (the harness itself is sound).
#[test]
fn the_base_config_runs_cleanly() {
    check(&toml::to_string(&base()).unwrap());
}

/// The problems `doc` is refused with, one string.
fn refusal(doc: &toml::Table) -> String {
    match Config::from_toml_str(&toml::to_string(doc).unwrap()) {
        Err(err @ SimError::Config(_)) => err.config_problems().join("\n"),
        other => panic!("expected a refusal, got {other:?}"),
    }
}

fn set(doc: &mut toml::Table, section: &str, key: &str, value: f64) {
    doc[section]
        .as_table_mut()
        .unwrap()
        .insert(key.into(), Value::Float(value));
}

/// Found by this target (seed 3): `objects.laptop_length` 6e5 m with `laptop_width` 0.2 mm put a
/// laptop's corners 300 km out, where 32-bit coordinates merged two of them, and ORCA's obstacle
/// processing panicked on the zero-length edge. Both sizes are refused now: a laptop must fit the
/// room and its table, and every size must be resolvable at the room's extent.
#[test]
fn regression_a_laptop_larger_than_the_room_or_too_thin_to_resolve_is_refused() {
    let mut doc = base();
    set(&mut doc, "objects", "laptop_length", 600000.0);
    set(&mut doc, "objects", "laptop_width", 0.000_215);
    let err = refusal(&doc);
    assert!(err.contains("room too small: a laptop"), "{err}");
    assert!(
        err.contains("`objects.laptop_length` 600000 m is more than `objects.table_length` 3 m"),
        "{err}"
    );
    let mut doc = base();
    set(&mut doc, "objects", "laptop_width", 0.000_05);
    let err = refusal(&doc);
    assert!(
        err.contains("`objects.laptop_width` 0.00005 m is too small for a room up to 10 m across"),
        "{err}"
    );
    set(&mut doc, "objects", "laptop_width", 0.001);
    check(&toml::to_string(&doc).unwrap());
}

/// Found by this target (seed 2): `laptop_use.human_distance` 3 m (exp3's 0.3 m times ten) with
/// three laptop users seated one 2.6 m outside the 10 m room, beyond the wall it jumped. A seat
/// out of reach of its laptop is refused now.
#[test]
fn regression_a_laptop_user_seated_out_of_reach_is_refused() {
    let mut doc = base();
    set(&mut doc, "laptop_use", "human_distance", 3.0);
    let err = refusal(&doc);
    assert!(
        err.contains(
            "`laptop_use.human_distance` 3 m seats a laptop's user 3.4 m from it, more than 1.5 m"
        ),
        "{err}"
    );
    set(&mut doc, "laptop_use", "human_distance", 1.1);
    doc["counts"]
        .as_table_mut()
        .unwrap()
        .insert("laptop_users".into(), Value::try_from([3, 3]).unwrap());
    check(&toml::to_string(&doc).unwrap());
}

/// The SocNavGym 0.1.1 config dict (`exp3_no_sngnn.yaml`, as the golden episode's header carries
/// the parsed YAML) that the SocNavGym target mutates; from the repository's copy of the golden
/// episodes, so that the target never skips.
fn socnavgym_base() -> serde_json::Value {
    use std::io::Read;
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/golden/socnavgym/exp3_no_sngnn_seed0.json.gz"
    );
    let mut text = String::new();
    flate2::read::GzDecoder::new(std::fs::File::open(path).unwrap())
        .read_to_string(&mut text)
        .unwrap();
    let root: serde_json::Value = serde_json::from_str(&text).unwrap();
    root["header"]["config"].clone()
}

/// What a mutated SocNavGym dict must do: load as a validated config (which then runs cleanly)
/// or be refused with `SimError::Config` listing its problems.
fn check_socnavgym(dict: &serde_json::Value) {
    let context = serde_json::to_string_pretty(dict).unwrap();
    loaded_or_refused(Config::from_socnavgym(dict), &context);
}

proptest! {
    #![proptest_config(super::config(48))]

    #[test]
    fn mutated_socnavgym_dicts_are_refused_clearly_or_run_cleanly(
        edits in prop::collection::vec((0usize..1000, 0u8..64, 0.0f64..1.0), 1..6),
        drop in prop::option::of(0usize..1000),
    ) {
        let mut dict = socnavgym_base();
        let paths = super::json::paths(&dict);
        for (pick, kind, x) in edits {
            super::json::mutate_at(&mut dict, &paths[pick % paths.len()], kind, x);
        }
        if let Some(pick) = drop {
            super::json::remove(&mut dict, &paths[pick % paths.len()]);
        }
        check_socnavgym(&dict);
    }
}

/// The unmutated SocNavGym dict passes the same check.
#[test]
fn the_base_socnavgym_dict_runs_cleanly() {
    check_socnavgym(&socnavgym_base());
}
/// Found by the SocNavGym target (seed 2): `noise_variance` 1e38 (a group member's velocity noise)
/// made the first observation non-finite; the noise also accumulates, walking members through
/// walls. It is refused now beyond about 1 m of drift over an episode.
#[test]
fn regression_group_noise_that_walks_members_away_is_refused() {
    let mut dict = socnavgym_base();
    dict["human-human-interaction"]["noise_variance"] = serde_json::json!(1e38);
    match Config::from_socnavgym(&dict) {
        Err(err @ SimError::Config(_)) => {
            let problems = err.config_problems().join("\n");
            assert!(
                problems.contains("`group.velocity_noise_std` 100000000000000000000000000000000000000 m/s walks a group member"),
                "{problems}"
            );
        }
        other => panic!("{other:?}"),
    }
    dict["human-human-interaction"]["noise_variance"] = serde_json::json!(0.07);
    check_socnavgym(&dict);
}
