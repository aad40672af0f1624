//! Scenario feasibility: any config that passes validation resets within a bounded time, or
//! fails with `SimError::Scenario` naming the environment and the entity that found no free spot.
//! Configs are drawn inside the bounds (room shapes and sizes, every count range, the sizes of
//! the robot, humans, groups and objects, the margin), so that most pass validation; those that
//! do not are discarded. The scenario sampler bounds its attempts (no wall-clock timeout as in
//! 0.1.1), so a reset that does not return within `LIMIT` is a hang and fails the target.

use std::sync::mpsc;
use std::time::Duration;

use proptest::prelude::*;
use socnav::{Actions, AutoresetMode, Config, SimError};
use toml::Value;

/// Far beyond the slowest valid reset seen (a few milliseconds for 8 environments): only a
/// hang reaches it.
const LIMIT: Duration = Duration::from_secs(120);

/// The entities the sampler names when it finds no free spot (`scenario::generate`).
const ENTITIES: [&str; 10] = [
    "the robot",
    "a lone human",
    "a plant",
    "a table",
    "a laptop",
    "a group",
    "a laptop user",
    "a human goal",
    "the robot goal",
    "a group goal",
];

#[derive(Debug, Clone)]
struct Draw {
    shape: &'static str,
    corridors: bool,
    size_x: [i64; 2],
    size_y: [i64; 2],
    margin: f64,
    /// (key, [lo, hi]) for each count.
    counts: Vec<(&'static str, [i64; 2])>,
    robot_radius: f64,
    human_diameter: f64,
    group_radius: f64,
    plant_radius: f64,
    table: [f64; 2],
    laptop: [f64; 2],
}

const COUNT_KEYS: [&str; 12] = [
    "static_humans",
    "dynamic_humans",
    "tables",
    "plants",
    "laptops",
    "moving_groups",
    "moving_groups_non_dispersing",
    "standing_groups",
    "standing_groups_non_dispersing",
    "group_size",
    "laptop_users",
    "laptop_users_non_dispersing",
];

fn range(max: i64) -> impl Strategy<Value = [i64; 2]> {
    (0..=max, 0..=3i64).prop_map(move |(lo, d)| [lo, (lo + d).min(max)])
}

fn draw() -> impl Strategy<Value = Draw> {
    let counts = (
        prop::collection::vec(range(6), 9),
        (2i64..=4, 0i64..=3),
        prop::collection::vec(range(3), 2),
    )
        .prop_map(|(mut most, (g, gd), users)| {
            most.push([g, g + gd]);
            most.extend(users);
            COUNT_KEYS.iter().copied().zip(most).collect::<Vec<_>>()
        });
    (
        prop::sample::select(vec!["square", "rectangle", "L", "random"]),
        any::<bool>(),
        (range(14), range(14)),
        0.0f64..1.0,
        counts,
        (0.1f64..0.8, 0.3f64..0.9, 0.3f64..1.0, 0.1f64..0.6),
        ((0.5f64..2.0, 1.0f64..3.5), (0.1f64..0.5, 0.1f64..0.7)),
    )
        .prop_map(
            |(shape, corridors, (sx, sy), margin, counts, radii, (table, laptop))| Draw {
                shape,
                corridors,
                size_x: [sx[0] + 4, sx[1] + 4],
                size_y: [sy[0] + 4, sy[1] + 4],
                margin,
                counts,
                robot_radius: radii.0,
                human_diameter: radii.1,
                group_radius: radii.2,
                plant_radius: radii.3,
                table: [table.0, table.1],
                laptop: [laptop.0, laptop.1],
            },
        )
}

/// Experiment 3's config with the drawn values, as TOML text.
fn config_text(d: &Draw) -> String {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/exp3.toml")).unwrap();
    let mut doc: toml::Table = text.parse().unwrap();
    let mut set = |section: &str, key: &str, value: Value| {
        doc[section]
            .as_table_mut()
            .unwrap()
            .insert(key.into(), value);
    };
    let pair = |r: [i64; 2]| Value::Array(vec![Value::Integer(r[0]), Value::Integer(r[1])]);
    set("room", "shape", Value::String(d.shape.into()));
    set("room", "corridors", Value::Boolean(d.corridors));
    set("room", "size_x", pair(d.size_x));
    set("room", "size_y", pair(d.size_y));
    set("room", "margin", Value::Float(d.margin));
    for (key, r) in &d.counts {
        set("counts", key, pair(*r));
    }
    set("robot", "radius", Value::Float(d.robot_radius));
    set("human", "diameter", Value::Float(d.human_diameter));
    set("group", "radius", Value::Float(d.group_radius));
    set("objects", "plant_radius", Value::Float(d.plant_radius));
    set("objects", "table_width", Value::Float(d.table[0]));
    set("objects", "table_length", Value::Float(d.table[1]));
    set("objects", "laptop_width", Value::Float(d.laptop[0]));
    set("objects", "laptop_length", Value::Float(d.laptop[1]));
    toml::to_string(&doc).unwrap()
}

/// Build, reset at `seed` and step the batch (its autoresets place new scenarios) on a thread:
/// `Ok` or a scenario error, or `None` if it did not finish within `LIMIT`.
fn reset_and_step(config: Config, seed: u64) -> Option<Result<(), SimError>> {
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        let run = || -> Result<(), SimError> {
            let mut env = super::batch(config, 8, seed, AutoresetMode::SameStep, 1)?;
            for _ in 0..30 {
                env.step(Actions::Discrete(&[0; 8]))?;
            }
            Ok(())
        };
        // The receiver may have given up (a hang): nothing is left to tell.
        let _ = send.send(run());
    });
    receive.recv_timeout(LIMIT).ok()
}

proptest! {
    #![proptest_config(proptest::test_runner::Config {
        max_global_rejects: 100_000,
        ..super::config(48)
    })]

    #[test]
    fn valid_configs_reset_in_bounded_time_or_name_the_entity_that_did_not_fit(
        d in draw(),
        seed in any::<u64>(),
    ) {
        let text = config_text(&d);
        let parsed = Config::from_toml_str(&text);
        prop_assume!(!matches!(parsed, Err(SimError::Config(_))), "outside the bounds");
        let config = parsed.unwrap_or_else(|e| panic!("{e:?}\n{text}"));
        match reset_and_step(config, seed) {
            None => panic!("no reset or step within {LIMIT:?} (seed {seed})\n{text}"),
            Some(Ok(())) => {}
            Some(Err(SimError::Scenario { env, entity, message })) => {
                prop_assert!(env < 8, "{}", message);
                prop_assert!(ENTITIES.contains(&entity.as_str()), "entity {:?}: {}", entity, message);
                prop_assert!(message.contains(&entity) && message.contains(&format!("environment {env}")), "{}", message);
            }
            Some(Err(e)) => panic!("a valid config fails with {e:?} (seed {seed})\n{text}"),
        }
    }
}

/// Found by this target (seed 2): an L room (`shape = "random"`) 11 x 7 m with corridors and a
/// robot 1.5 m across drew a corridor door wider than its short wall line; the pieces beside the
/// door got negative lengths and a contact test panicked (`clamp` with min > max), which the
/// batch reported as an internal error. The door now spans at most its line.
#[test]
fn regression_a_door_wider_than_its_corridor_line_spans_it() {
    let count = |key: &'static str, r: [i64; 2]| (key, r);
    let d = Draw {
        shape: "random",
        corridors: true,
        size_x: [11, 11],
        size_y: [7, 7],
        margin: 0.0,
        counts: vec![
            count("static_humans", [0, 0]),
            count("dynamic_humans", [0, 2]),
            count("tables", [1, 3]),
            count("plants", [0, 0]),
            count("laptops", [0, 0]),
            count("moving_groups", [0, 0]),
            count("moving_groups_non_dispersing", [0, 0]),
            count("standing_groups", [0, 0]),
            count("standing_groups_non_dispersing", [0, 0]),
            count("group_size", [2, 2]),
            count("laptop_users", [0, 0]),
            count("laptop_users_non_dispersing", [0, 0]),
        ],
        robot_radius: 0.7464766542204634,
        human_diameter: 0.3,
        group_radius: 0.3,
        plant_radius: 0.1,
        table: [0.5, 1.0],
        laptop: [0.1, 0.1],
    };
    let config = Config::from_toml_str(&config_text(&d)).unwrap();
    match reset_and_step(config, 10_524_287_534_628_775_006) {
        Some(Ok(()) | Err(SimError::Scenario { .. })) => {}
        other => panic!("{other:?}"),
    }
}
