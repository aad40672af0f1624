//! Configuration loading and validation (docs/spec.md, layout and style rule 8; docs/spec.md 2).
//!
//! Contracts checked here:
//! - every shipped `configs/*.toml` parses and validates, and `Config::default()` is exactly
//!   `configs/exp1.toml` (the defaults reproduce the paper's experiment 1);
//! - a config with many mistakes is rejected with *every* problem listed at once, each message
//!   naming the key and the offending value, values that do not deserialise (an unknown
//!   variant, a wrong type) included;
//! - a partial TOML file takes the defaults for every key it does not set;
//! - `Config::from_socnavgym` turns a SocNavGym 0.1.1 config dict into exactly the shipped TOML
//!   of the same stem (checked on the golden episode headers), and reports missing 0.1.1 keys.
//!
//! Environment: `SOCNAV_GOLDEN_DIR` (default `tests/data/golden/socnavgym`); without that
//! directory the golden part is skipped with a printed reason.

use std::io::Read;
use std::path::{Path, PathBuf};

use serde_json::{Value, json};
use socnav::{Config, SimError};

fn configs_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs")
}

/// Every `configs/*.toml`, sorted by name.
fn shipped_configs() -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(configs_dir())
        .expect("configs/ exists")
        .map(|e| e.expect("readable configs/ entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    paths
}

/// The problems of a rejected config, or a panic naming what was returned instead.
fn config_problems(result: Result<Config, SimError>) -> Vec<String> {
    match result {
        Err(err @ SimError::Config(_)) => err.config_problems(),
        other => panic!("expected SimError::Config, got {other:?}"),
    }
}

/// Contract: every shipped config file loads without a single problem.
#[test]
fn every_shipped_config_parses_and_validates() {
    let paths = shipped_configs();
    for path in &paths {
        let config = Config::from_file(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            socnav::config::validate(&config).is_empty(),
            "{}",
            path.display()
        );
        // The name-based lookup the CLI and Python use finds the same file.
        let stem = path.file_stem().unwrap().to_str().unwrap();
        assert_eq!(Config::from_name_or_path(stem).unwrap(), config, "{stem}");
    }
    // The paper's three experiments and the golden set's two derived configs at least.
    assert!(
        paths.len() >= 5,
        "only {} configs found in configs/",
        paths.len()
    );
}

/// Contract: the defaults are the paper's experiment 1, key for key.
#[test]
fn default_config_is_exp1() {
    let exp1 = Config::from_file(configs_dir().join("exp1.toml")).unwrap();
    assert_eq!(Config::default(), exp1);
    // Serialising the defaults and reading them back is the identity (every key has a name).
    assert_eq!(
        Config::from_toml_str(&Config::default().to_toml_string()).unwrap(),
        exp1
    );
}

/// Contract (docs/spec.md, style rule 8): every problem is reported at once, each naming its key
/// and value. The file below has seven independent mistakes; each must appear in the one error.
#[test]
fn every_problem_is_listed_at_once() {
    let text = r#"
        [robot]
        wheel_base = 0.3            # unknown key

        [objects]
        plant_radius = -0.4         # negative size

        [events]
        laptop_dispersal_probability = 1.5   # not a probability

        [room]
        size_x = [2, 12]            # the smallest (2 m) square room cannot hold a table

        [counts]
        static_humans = [3, 1]      # min > max
        standing_groups = [1, 1]
        group_size = [1, 2]         # groups of one
        tables = [0, 1]
        laptop_users = [1, 1]       # laptop users, but maybe no table
    "#;
    let problems = config_problems(Config::from_toml_str(text));
    let all = problems.join("\n");
    println!("reported problems:\n{all}");
    // (what, substrings that the message of that problem must contain)
    let expected: [(&str, &[&str]); 7] = [
        ("unknown key", &["robot.wheel_base"]),
        ("negative size", &["objects.plant_radius", "-0.4"]),
        (
            "probability 1.5",
            &["events.laptop_dispersal_probability", "1.5"],
        ),
        ("min > max", &["counts.static_humans", "3", "1"]),
        ("group of one", &["counts.group_size", "got 1"]),
        (
            "laptop users without tables",
            &["counts.tables", "laptop_users", "got 0"],
        ),
        ("room too small for a table", &["room.size_x", "2", "table"]),
    ];
    for (what, needles) in expected {
        let hit = problems
            .iter()
            .any(|p| needles.iter().all(|n| p.contains(n)));
        assert!(
            hit,
            "no message about {what} containing all of {needles:?}; got:\n{all}"
        );
    }
    // One message per problem: the seven mistakes above, plus at most a few consequences
    // (e.g. a group that does not fit either), never one message hiding the others.
    assert!(
        problems.len() >= expected.len(),
        "{} messages for {} problems",
        problems.len(),
        expected.len()
    );
}

/// Contract: a value that does not deserialise (an unknown variant of a named option, a wrong
/// type) is reported with its key and value, together with every other problem of the file.
#[test]
fn bad_option_values_are_listed_with_the_other_problems() {
    let text = r#"
        [objects]
        plant_radius = -0.4                  # negative size

        [model]
        contact_shape = "polygon32"          # not a contact shape
        laptop_user_obstacle = 3             # not a string
        orca_neighbour_velocity = "actual"
    "#;
    let problems = config_problems(Config::from_toml_str(text));
    let all = problems.join("\n");
    println!("reported problems:\n{all}");
    for needles in [
        &["model.contact_shape", "polygon32", "exact", "polygon64"][..],
        &["model.laptop_user_obstacle", "3"],
        &["objects.plant_radius", "-0.4"],
    ] {
        assert!(
            problems
                .iter()
                .any(|p| needles.iter().all(|n| p.contains(n))),
            "no message containing all of {needles:?}; got:\n{all}"
        );
    }
    assert_eq!(problems.len(), 3, "{all}");
    // The same through overrides.
    let base = Config::from_name_or_path("exp1").unwrap();
    let problems = config_problems(base.with_overrides(&json!({
        "model": {"contact_shape": "disc"},
        "episode": {"length": 100, "lenght": 3},
    })));
    assert!(
        problems
            .iter()
            .any(|p| p.contains("contact_shape") && p.contains("disc")),
        "{problems:?}"
    );
    assert!(
        problems.iter().any(|p| p.contains("lenght")),
        "{problems:?}"
    );
}

/// Contract: counts beyond what the step's fixed scratch holds are rejected up front, naming
/// the limit and where the number comes from (the room check may add its own complaint).
#[test]
fn counts_beyond_the_per_environment_limits_are_rejected() {
    let mut config = Config::default();
    config.room.size_x = [200, 200];
    config.counts.standing_groups = [0, 4];
    config.counts.group_size = [2, 80];
    config.counts.static_humans = [0, 10];
    config.counts.laptops = [0, 300];
    let problems = socnav::config::validate(&config);
    let all = problems.join("\n");
    for needles in [
        &["counts.group_size", "at most 64", "80"][..],
        &[
            "at most 256 humans",
            "331",
            "static 10 + dynamic 1",
            "groups 4 x group size 80",
        ],
        &["at most 256 laptops", "300"],
        &["at most 256 ORCA obstacles", "`counts` allow"],
    ] {
        assert!(
            problems
                .iter()
                .any(|p| needles.iter().all(|n| p.contains(n))),
            "no message containing all of {needles:?}; got:\n{all}"
        );
    }
}

/// Contract: counts whose sums pass `i32` (each one a valid range on its own) are reported, not
/// wrapped into a small number that the checks built on them would pass (a batch with no group
/// capacity that draws a billion groups).
#[test]
fn counts_that_sum_past_i32_are_refused_not_wrapped() {
    let mut config = Config::default();
    config.counts.moving_groups = [0, i32::MAX];
    config.counts.moving_groups_non_dispersing = [0, 1];
    config.counts.group_size = [2, 2];
    config.counts.laptop_users = [0, i32::MAX];
    config.counts.laptop_users_non_dispersing = [0, 1];
    config.counts.tables = [1, 1];
    let all = socnav::config::validate(&config).join("\n");
    for needle in [
        "at most 256 humans",
        "6442450945",
        "laptop users 2147483648",
        "at most 256 laptops",
    ] {
        assert!(all.contains(needle), "no {needle:?} in:\n{all}");
    }
}

/// Contract: every array of a config is `[min, max]`; a longer one is refused by key (serde
/// takes the first two items of it without a word), with the other problems.
#[test]
fn a_range_of_more_than_two_items_is_refused() {
    let problems = config_problems(Config::from_toml_str(
        "[counts]\nstatic_humans = [0, 1, 2]\n[room]\nsize_x = [8, 9, 10, 11]\n[episode]\nlenght = 3\n",
    ));
    let all = problems.join("\n");
    for needle in [
        "`counts.static_humans` must be [min, max], got an array of 3 items",
        "`room.size_x` must be [min, max], got an array of 4 items",
        "episode.lenght",
    ] {
        assert!(all.contains(needle), "no {needle:?} in:\n{all}");
    }
    let overridden =
        Config::default().with_overrides(&serde_json::json!({"counts": {"plants": [0, 1, 2]}}));
    assert!(
        config_problems(overridden)
            .iter()
            .any(|p| p.contains("`counts.plants` must be [min, max]")),
    );
}

/// Contract: a step shorter than a millisecond is refused (at 1e-12 s the step's sums lose
/// its motion and the outputs go non-finite; with SNGNN-v2 the history would hold 2e12 frames).
#[test]
fn a_time_step_below_a_millisecond_is_refused() {
    for dt in [1e-12, 1e-4, 0.0, -1.0, f32::NAN, f32::INFINITY] {
        let mut config = Config::default();
        config.episode.time_step = dt;
        let all = socnav::config::validate(&config).join("\n");
        assert!(
            all.contains("`episode.time_step` must be a finite number of at least 0.001 s"),
            "{dt}: {all}"
        );
    }
    let mut config = Config::default();
    config.episode.time_step = 1e-3;
    config.robot.max_speed = 0.01;
    config.human.max_speed = 0.01;
    let all = socnav::config::validate(&config).join("\n");
    assert!(!all.contains("time_step"), "{all}");
}

/// Contract: `BatchEnv::new` applies the same validation to a `Config` built in code.
#[test]
fn batch_rejects_an_invalid_config_built_in_code() {
    let mut config = Config::default();
    config.robot.radius = -1.0;
    config.events.crowd_formation_probability = 2.0;
    let err = socnav::BatchEnv::new(config, socnav::EnvOptions::default()).unwrap_err();
    let SimError::Config(problems) = err else {
        panic!("expected SimError::Config, got {err:?}")
    };
    // Each problem carries the key it is about, for a caller to branch on.
    assert!(
        problems
            .iter()
            .any(|p| p.key.as_deref() == Some("robot.radius") && p.message.contains("-1")),
        "{problems:?}"
    );
    assert!(problems.iter().any(|p| {
        p.key.as_deref() == Some("events.crowd_formation_probability") && p.message.contains('2')
    }));
}

/// Contract: a partial TOML file takes the defaults for every key it does not set.
#[test]
fn partial_toml_fills_defaults() {
    assert_eq!(Config::from_toml_str("").unwrap(), Config::default());
    let config =
        Config::from_toml_str("[robot]\nradius = 0.3\n\n[counts]\nplants = [0, 2]\n").unwrap();
    let mut expected = Config::default();
    expected.robot.radius = 0.3;
    expected.counts.plants = [0, 2];
    assert_eq!(config, expected);
    // A section that sets one key keeps the section's other defaults.
    assert_eq!(
        config.robot.goal_radius,
        Config::default().robot.goal_radius
    );
}

/// Contract: a file far larger than any config (`/dev/zero`, a dataset given by mistake) is
/// refused after its first mebibyte, not read whole.
#[test]
fn a_file_larger_than_a_config_is_refused_unread() {
    let path = std::env::temp_dir().join(format!("socnav-big-config-{}.toml", std::process::id()));
    std::fs::write(&path, "#".repeat((1 << 20) + 1)).unwrap();
    let problems = config_problems(Config::from_file(&path));
    std::fs::remove_file(&path).unwrap();
    assert!(
        problems
            .iter()
            .any(|p| p.contains("larger than 1048576 bytes")),
        "{problems:?}"
    );
    if Path::new("/dev/zero").exists() {
        assert!(Config::from_file("/dev/zero").is_err());
    }
}

/// Contract: a file that is not TOML at all is a config error, not a panic.
#[test]
fn malformed_toml_is_a_config_error() {
    let problems = config_problems(Config::from_toml_str("[robot\nradius = "));
    assert!(!problems.is_empty());
    // A machine-written config of one long line is not quoted whole.
    let long = format!("[robot]\nradius = \"{}", "a".repeat(100_000));
    let problems = config_problems(Config::from_toml_str(&long));
    assert!(
        problems.iter().all(|p| p.len() < 3_000) && problems.iter().any(|p| p.contains("in all")),
        "{:?}",
        problems.iter().map(String::len).collect::<Vec<_>>()
    );
}

/// SocNavGym 0.1.1's `exp1_no_sngnn.yaml` as a JSON dict (docs/spec.md 2.1), written out by hand
/// so that the import is tested without the golden files.
fn exp1_socnavgym_dict() -> Value {
    serde_json::from_str(
        r#"{
        "rendering": {"resolution_view": 1000, "milliseconds": 30},
        "episode": {"episode_length": 200, "time_step": 1},
        "robot": {"robot_radius": 0.25, "goal_radius": 0.35, "robot_type": "diff-drive"},
        "human": {"human_diameter": 0.72, "human_goal_radius": 0.25, "human_policy": "random",
                  "gaze_angle": 3.14159, "fov_angle": 6.2831853, "prob_to_avoid_robot": 0.0},
        "laptop": {"laptop_width": 0.4, "laptop_length": 0.6},
        "plant": {"plant_radius": 0.4},
        "table": {"table_width": 1.5, "table_length": 3.0},
        "wall": {"wall_thickness": 0.2},
        "human-human-interaction": {"interaction_radius": 0.72, "interaction_goal_radius": 1.44,
                                    "noise_variance": 0.005},
        "human-laptop-interaction": {"human_laptop_distance": 0.3},
        "env": {
            "margin": 0.5, "max_advance_human": 0.1, "max_advance_robot": 0.1, "max_rotation": 0.387596899,
            "wall_segment_size": 1.0, "speed_threshold": 0.005, "crowd_dispersal_probability": 0.0,
            "human_laptop_dispersal_probability": 0.0, "crowd_formation_probability": 0.0,
            "human_laptop_formation_probability": 0.0, "reward_file": "dsrnn", "cuda_device": 0,
            "min_static_humans": 0, "max_static_humans": 0, "min_dynamic_humans": 1, "max_dynamic_humans": 1,
            "min_tables": 0, "max_tables": 0, "min_plants": 1, "max_plants": 1, "min_laptops": 0,
            "max_laptops": 0, "min_h_h_dynamic_interactions": 0, "max_h_h_dynamic_interactions": 0,
            "min_h_h_dynamic_interactions_non_dispersing": 0, "max_h_h_dynamic_interactions_non_dispersing": 0,
            "min_h_h_static_interactions": 0, "max_h_h_static_interactions": 0,
            "min_h_h_static_interactions_non_dispersing": 0, "max_h_h_static_interactions_non_dispersing": 0,
            "min_human_in_h_h_interactions": 0, "max_human_in_h_h_interactions": 0,
            "min_h_l_interactions": 0, "max_h_l_interactions": 0,
            "min_h_l_interactions_non_dispersing": 0, "max_h_l_interactions_non_dispersing": 0,
            "get_padded_observations": false, "set_shape": "square", "add_corridors": false,
            "min_map_x": 10, "max_map_x": 10, "min_map_y": 10, "max_map_y": 10
        }
    }"#,
    )
    .expect("valid JSON")
}

/// Contract: the 0.1.1 import of experiment 1's YAML is the default config.
#[test]
fn socnavgym_exp1_dict_imports_as_default() {
    assert_eq!(
        Config::from_socnavgym(&exp1_socnavgym_dict()).unwrap(),
        Config::default()
    );
}

/// Contract (docs/spec.md 2: every 0.1.1 key is mandatory): each missing key is reported, by its
/// `section.key` name, all in one error.
#[test]
fn socnavgym_missing_keys_are_reported() {
    let mut dict = exp1_socnavgym_dict();
    dict["env"]
        .as_object_mut()
        .unwrap()
        .remove("max_advance_robot");
    dict["robot"]
        .as_object_mut()
        .unwrap()
        .remove("robot_radius");
    dict["env"].as_object_mut().unwrap().remove("min_tables");
    // An integer past i32 is named, not wrapped (4294967306 would have read as 10).
    dict["env"]["max_tables"] = serde_json::json!(4_294_967_306_i64);
    let problems = config_problems(Config::from_socnavgym(&dict));
    for key in [
        "env.max_advance_robot",
        "robot.robot_radius",
        "env.min_tables",
        "`env.max_tables` is 4294967306, outside the 32-bit integers",
    ] {
        assert!(
            problems.iter().any(|p| p.contains(key)),
            "`{key}` not reported in {problems:?}"
        );
    }
    // A whole missing section names its keys too.
    let mut dict = exp1_socnavgym_dict();
    dict.as_object_mut().unwrap().remove("plant");
    let problems = config_problems(Config::from_socnavgym(&dict));
    assert!(
        problems.iter().any(|p| p.contains("plant.plant_radius")),
        "{problems:?}"
    );
    // A value of the wrong type is reported with its key.
    let mut dict = exp1_socnavgym_dict();
    dict["robot"]["robot_type"] = json!("tank");
    let problems = config_problems(Config::from_socnavgym(&dict));
    assert!(
        problems
            .iter()
            .any(|p| p.contains("robot.robot_type") && p.contains("tank")),
        "{problems:?}"
    );
}

/// The `header.config` dict of the first golden episode of `config_name`, if the golden
/// directory holds one.
fn golden_header_config(dir: &Path, config_name: &str) -> Option<Value> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with(&format!("{config_name}_seed")) && n.ends_with(".json.gz"))
        .collect();
    names.sort();
    let path = dir.join(names.first()?);
    let mut text = String::new();
    flate2::read::GzDecoder::new(std::fs::File::open(&path).unwrap())
        .read_to_string(&mut text)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let root: Value =
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Some(root["header"]["config"].clone())
}

/// The golden configs (0.1.1's file stems) and their shipped twins (`configs/<stem>.toml`).
const GOLDEN_TWINS: [(&str, &str); 7] = [
    ("exp1_no_sngnn", "exp1"),
    ("exp2_no_sngnn", "exp2"),
    ("exp3_no_sngnn", "exp3"),
    ("exp1_with_sngnn", "exp1_sngnn"),
    ("exp2_with_sngnn", "exp2_sngnn"),
    ("lroom_mixed", "lroom_mixed"),
    ("corridor_mixed", "corridor_mixed"),
];

/// The SocNavGym 0.1.1 YAML files the golden episodes were recorded with.
fn golden_yaml(stem: &str) -> PathBuf {
    crate::golden::published_dir()
        .join("configs")
        .join(format!("{stem}.yaml"))
}

/// Contract: a SocNavGym 0.1.1 YAML file is a config wherever a path is taken
/// (`Config::from_file`, `from_name_or_path`), parsed in the library, and gives exactly the
/// shipped twin, so the same trajectories.
#[test]
fn socnavgym_yaml_files_load_as_their_shipped_twins() {
    for (golden, stem) in GOLDEN_TWINS {
        let path = golden_yaml(golden);
        let ours = Config::from_file(configs_dir().join(format!("{stem}.toml"))).unwrap();
        let theirs = Config::from_file(&path).unwrap_or_else(|e| panic!("{golden}.yaml: {e}"));
        assert_eq!(
            ours, theirs,
            "{golden}.yaml differs from configs/{stem}.toml"
        );
        let by_name = Config::from_name_or_path(path.to_str().unwrap()).unwrap();
        assert_eq!(ours, by_name);
    }
    // `.yml` and any case of the extension are YAML too; the text is the same.
    let dir = tempdir("yml");
    let yml = dir.join("exp2.YML");
    std::fs::copy(golden_yaml("exp2_no_sngnn"), &yml).unwrap();
    assert_eq!(
        Config::from_file(&yml).unwrap(),
        Config::from_name_or_path("exp2").unwrap()
    );
}

/// A fresh directory under the target directory for one test's files.
fn tempdir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("config_validation_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Contract: a SocNavGym YAML file's problems come all at once, each naming its key and the file:
/// a key 0.1.1 does not read, the two keys of a later SocNavGym version (saying so), a section of
/// its own, a value JSON cannot hold (named once, not again as mistyped), a custom reward file
/// (pointing at `reward_fn`), and a mistyped boolean; PyYAML's `yes`/`no`/`on`/`off` are booleans.
#[test]
fn socnavgym_yaml_problems_are_reported_together() {
    let text = std::fs::read_to_string(golden_yaml("exp1_no_sngnn")).unwrap();
    let replace = |text: &str, from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        text.replacen(from, to, 1)
    };
    let mut bad = replace(
        &text,
        "  episode_length: 200\n",
        "  episode_length: 200\n  end_with_collision: True\n",
    );
    bad = replace(
        &bad,
        "  reward_file: dsrnn\n",
        "  reward_file: my_reward\n  max_rotation_human: 1.57\n  colour: red\n",
    );
    bad = replace(&bad, "  margin: 0.5\n", "  margin: .nan\n");
    bad = replace(&bad, "  add_corridors: false\n", "  add_corridors: maybe\n");
    bad.push_str("chair:\n  chair_radius: 0.3\n");
    let dir = tempdir("yaml_problems");
    let path = dir.join("bad.yaml");
    std::fs::write(&path, &bad).unwrap();
    let problems = config_problems(Config::from_file(&path));
    let expected = [
        "`env.margin` must be a finite number, got .nan",
        "`env.reward_file` \"my_reward\"",
        "`env.add_corridors` must be true or false",
        "`chair` is not a section of SocNavGym 0.1.1's config",
        "`env.colour` is not a key of SocNavGym 0.1.1's config",
        "`env.max_rotation_human` belongs to a later SocNavGym version",
        "`episode.end_with_collision` belongs to a later SocNavGym version",
    ];
    assert_eq!(problems.len(), expected.len(), "{problems:#?}");
    for (problem, text) in problems.iter().zip(expected) {
        assert!(problem.contains(text), "{problem:?} lacks {text:?}");
        assert!(
            problem.starts_with(&format!("{}: ", path.display())),
            "{problem}"
        );
    }
    assert!(problems[1].contains("`reward_fn`"), "{}", problems[1]);

    // YAML 1.1 booleans, as 0.1.1's PyYAML reads them.
    let yes = replace(&text, "  add_corridors: false\n", "  add_corridors: yes\n");
    let yes = replace(
        &yes,
        "  get_padded_observations: false\n",
        "  get_padded_observations: On\n",
    );
    let path = dir.join("yes.yaml");
    std::fs::write(&path, yes).unwrap();
    let config = Config::from_file(&path).unwrap();
    assert!(config.room.corridors && config.observation.padded);

    // Not YAML, not a mapping, two documents.
    for (name, text, expected) in [
        ("broken.yaml", "a: [\n", "not valid YAML"),
        (
            "list.yaml",
            "- a\n- b\n",
            "a mapping of sections, got a list",
        ),
        ("two.yaml", "a: 1\n---\nb: 2\n", "one YAML document, got 2"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let problems = config_problems(Config::from_file(&path));
        assert!(
            problems.len() == 1 && problems[0].contains(expected),
            "{name}: {problems:?}"
        );
    }
}

/// Contract (docs/spec.md, fidelity: the replay rules): the config a golden episode was recorded
/// with, imported with `Config::from_socnavgym`, is exactly `configs/<stem>.toml`.
#[test]
fn golden_socnavgym_configs_equal_shipped_tomls() {
    let Some(dir) =
        crate::golden::golden_dir_or_skip("golden_socnavgym_configs_equal_shipped_tomls")
    else {
        return;
    };
    let pairs = GOLDEN_TWINS;
    let mut checked = 0;
    for (golden, stem) in pairs {
        let Some(dict) = golden_header_config(&dir, golden) else {
            panic!(
                "the golden directory {} has no `{golden}` episode",
                dir.display()
            );
        };
        let theirs = Config::from_socnavgym(&dict).unwrap_or_else(|e| panic!("{golden}: {e}"));
        let ours = Config::from_file(configs_dir().join(format!("{stem}.toml"))).unwrap();
        assert_eq!(
            ours, theirs,
            "configs/{stem}.toml differs from the golden `{golden}` header"
        );
        checked += 1;
    }
    assert_eq!(checked, pairs.len());
}

/// Contract: every `configs/*.toml` is built into the library under its stem (so the names work
/// in an installed binary, away from the source tree), and nothing else is.
#[test]
fn every_config_file_is_shipped_by_name() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|n| n.strip_suffix(".toml").map(str::to_string))
        .collect();
    files.sort();
    let mut shipped: Vec<String> = socnav::Config::shipped_names()
        .map(str::to_string)
        .collect();
    shipped.sort();
    assert!(!files.is_empty());
    assert_eq!(
        files, shipped,
        "configs/*.toml and Config::shipped_names() differ"
    );
    for name in &shipped {
        let by_name = socnav::Config::from_name_or_path(name).unwrap();
        let by_file = socnav::Config::from_file(dir.join(format!("{name}.toml"))).unwrap();
        assert_eq!(by_name, by_file, "{name}");
    }
}

#[test]
fn overrides_merge_key_by_key_and_are_validated() {
    let base = Config::from_name_or_path("exp2").unwrap();
    let c = base
        .with_overrides(&json!({"episode": {"length": 100}, "counts": {"plants": [1, 3]}}))
        .unwrap();
    assert_eq!(c.episode.length, 100);
    assert_eq!(c.counts.plants, [1, 3]);
    // Everything else is the base config's.
    let mut expected = base.clone();
    expected.episode.length = 100;
    expected.counts.plants = [1, 3];
    assert_eq!(c, expected);

    // `null` restores the default of an optional key.
    let limited = base
        .with_overrides(&json!({"observation": {"range": 3.0}}))
        .unwrap();
    assert_eq!(limited.observation.range, Some(3.0));
    let unlimited = limited
        .with_overrides(&json!({"observation": {"range": null}}))
        .unwrap();
    assert_eq!(unlimited.observation.range, None);

    // Unknown keys, bad values and bad shapes are named, all at once.
    let problems = config_problems(base.with_overrides(&json!({
        "episode": {"lenght": 100},
        "counts": {"plants": [3, 1]},
    })));
    assert!(
        problems.iter().any(|p| p.contains("lenght")),
        "{problems:?}"
    );
    assert!(
        problems.iter().any(|p| p.contains("plants")),
        "{problems:?}"
    );
    let problems = config_problems(base.with_overrides(&json!({"episode": 3})));
    assert!(
        problems.iter().any(|p| p.contains("`episode`")),
        "{problems:?}"
    );
    let problems = config_problems(base.with_overrides(&json!([1, 2])));
    assert!(problems.iter().any(|p| p.contains("table")), "{problems:?}");
}
