//! Import of a SocNavGym 0.1.1 configuration into a socnav [`Config`]: its YAML file ([`parse_yaml`]
//! gives the JSON value that the golden episodes' headers also carry), then [`convert`]. Every key
//! of 0.1.1 is mandatory there, so a missing key is an error here too, and a key 0.1.1 does not
//! read is refused (one of a later SocNavGym version says so); all problems are reported together.

use std::collections::BTreeSet;

use serde_json::{Map, Number, Value};
use yaml_rust2::{Yaml, YamlLoader};

use super::{Config, HumanPolicy, Kinematics, RewardKind, Shape};
use crate::error::SimError;

/// Reads typed values out of the nested YAML dict and collects every problem.
struct Reader<'a> {
    root: &'a Value,
    problems: Vec<String>,
    /// The `(section, key)` pairs read, so that any other key can be refused.
    read: BTreeSet<(String, String)>,
}

impl<'a> Reader<'a> {
    fn get(&mut self, section: &str, key: &str) -> Option<&'a Value> {
        self.read.insert((section.to_owned(), key.to_owned()));
        let value = self.root.get(section).and_then(|s| s.get(key));
        if value.is_none() {
            self.problems
                .push(format!("SocNavGym config lacks `{section}.{key}`"));
        }
        value
    }

    fn f32(&mut self, section: &str, key: &str) -> f32 {
        match self.get(section, key).map(Value::as_f64) {
            Some(Some(x)) => x as f32,
            Some(None) => {
                self.problems
                    .push(format!("SocNavGym `{section}.{key}` must be a number"));
                0.0
            }
            None => 0.0,
        }
    }

    fn int(&mut self, section: &str, key: &str) -> i32 {
        match self.get(section, key).map(Value::as_i64) {
            Some(Some(x)) => i32::try_from(x).unwrap_or_else(|_| {
                self.problems.push(format!(
                    "SocNavGym `{section}.{key}` is {x}, outside the 32-bit integers socnav takes"
                ));
                0
            }),
            Some(None) => {
                self.problems
                    .push(format!("SocNavGym `{section}.{key}` must be an integer"));
                0
            }
            None => 0,
        }
    }

    fn range(&mut self, key: &str) -> [i32; 2] {
        [
            self.int("env", &format!("min_{key}")),
            self.int("env", &format!("max_{key}")),
        ]
    }

    fn string(&mut self, section: &str, key: &str) -> String {
        match self.get(section, key).map(Value::as_str) {
            Some(Some(s)) => s.to_string(),
            Some(None) => {
                self.problems
                    .push(format!("SocNavGym `{section}.{key}` must be a string"));
                String::new()
            }
            None => String::new(),
        }
    }

    fn bool(&mut self, section: &str, key: &str) -> bool {
        match self.get(section, key).map(yaml11_bool) {
            Some(Some(b)) => b,
            Some(None) => {
                self.problems
                    .push(format!("SocNavGym `{section}.{key}` must be true or false"));
                false
            }
            None => false,
        }
    }
}

/// Convert the 0.1.1 dict; validation is left to the caller.
pub(super) fn convert(yaml: &Value) -> Result<Config, SimError> {
    let mut r = Reader {
        root: yaml,
        problems: Vec::new(),
        read: BTreeSet::new(),
    };
    if !yaml.is_object() {
        return Err(SimError::config([format!(
            "a SocNavGym config is a mapping of sections, got {}",
            kind(yaml)
        )]));
    }
    let mut c = Config::default();
    c.render.resolution = r.int("rendering", "resolution_view").max(0) as u32;
    c.render.frame_ms = r.int("rendering", "milliseconds").max(0) as u32;
    c.episode.length = r.int("episode", "episode_length").max(0) as u32;
    c.episode.time_step = r.f32("episode", "time_step");
    c.robot.radius = r.f32("robot", "robot_radius");
    c.robot.goal_radius = r.f32("robot", "goal_radius");
    c.robot.kinematics = match r.string("robot", "robot_type").as_str() {
        "diff-drive" => Kinematics::DiffDrive,
        "holonomic" => Kinematics::Holonomic,
        other => {
            r.problems.push(format!(
                "SocNavGym `robot.robot_type` {other:?} is not diff-drive or holonomic"
            ));
            Kinematics::DiffDrive
        }
    };
    c.human.diameter = r.f32("human", "human_diameter");
    c.human.goal_radius = r.f32("human", "human_goal_radius");
    c.human.policy = match r.string("human", "human_policy").as_str() {
        "random" => HumanPolicy::Random,
        "orca" => HumanPolicy::Orca,
        "sfm" => HumanPolicy::Sfm,
        other => {
            r.problems.push(format!(
                "SocNavGym `human.human_policy` {other:?} is not random, orca or sfm"
            ));
            HumanPolicy::Random
        }
    };
    c.human.gaze_angle = r.f32("human", "gaze_angle");
    c.human.fov_angle = r.f32("human", "fov_angle");
    c.human.prob_to_avoid_robot = r.f32("human", "prob_to_avoid_robot");
    c.objects.laptop_width = r.f32("laptop", "laptop_width");
    c.objects.laptop_length = r.f32("laptop", "laptop_length");
    c.objects.plant_radius = r.f32("plant", "plant_radius");
    c.objects.table_width = r.f32("table", "table_width");
    c.objects.table_length = r.f32("table", "table_length");
    c.objects.wall_thickness = r.f32("wall", "wall_thickness");
    c.group.radius = r.f32("human-human-interaction", "interaction_radius");
    c.group.goal_radius = r.f32("human-human-interaction", "interaction_goal_radius");
    c.group.velocity_noise_std = r.f32("human-human-interaction", "noise_variance");
    c.laptop_use.human_distance = r.f32("human-laptop-interaction", "human_laptop_distance");
    c.room.margin = r.f32("env", "margin");
    c.human.max_speed = r.f32("env", "max_advance_human");
    c.robot.max_speed = r.f32("env", "max_advance_robot");
    c.robot.max_rotation = r.f32("env", "max_rotation");
    c.objects.wall_segment_size = r.f32("env", "wall_segment_size");
    c.human.speed_threshold = r.f32("env", "speed_threshold");
    c.events.crowd_dispersal_probability = r.f32("env", "crowd_dispersal_probability");
    c.events.laptop_dispersal_probability = r.f32("env", "human_laptop_dispersal_probability");
    c.events.crowd_formation_probability = r.f32("env", "crowd_formation_probability");
    c.events.laptop_formation_probability = r.f32("env", "human_laptop_formation_probability");
    c.reward.kind = match r.string("env", "reward_file").as_str() {
        "dsrnn" => RewardKind::Dsrnn,
        "sngnn" => RewardKind::Sngnn,
        other => {
            r.problems.push(format!(
                "SocNavGym `env.reward_file` {other:?}: socnav imports the built-in dsrnn and sngnn \
                 rewards; a reward of your own goes through `reward_fn` (Python) on top of one of \
                 them"
            ));
            RewardKind::Dsrnn
        }
    };
    // `cuda_device` picks a GPU in 0.1.1; socnav selects its backend at run time instead.
    let _ = r.int("env", "cuda_device");
    let n = &mut c.counts;
    n.static_humans = r.range("static_humans");
    n.dynamic_humans = r.range("dynamic_humans");
    n.tables = r.range("tables");
    n.plants = r.range("plants");
    n.laptops = r.range("laptops");
    n.moving_groups = r.range("h_h_dynamic_interactions");
    n.moving_groups_non_dispersing = r.range("h_h_dynamic_interactions_non_dispersing");
    n.standing_groups = r.range("h_h_static_interactions");
    n.standing_groups_non_dispersing = r.range("h_h_static_interactions_non_dispersing");
    n.group_size = r.range("human_in_h_h_interactions");
    n.laptop_users = r.range("h_l_interactions");
    n.laptop_users_non_dispersing = r.range("h_l_interactions_non_dispersing");
    c.observation.padded = r.bool("env", "get_padded_observations");
    c.room.shape = match r.string("env", "set_shape").as_str() {
        "square" => Shape::Square,
        "rectangle" => Shape::Rectangle,
        "L" => Shape::L,
        "no-walls" => Shape::NoWalls,
        "random" => Shape::Random,
        other => {
            r.problems.push(format!(
                "SocNavGym `env.set_shape` {other:?} is not a known shape"
            ));
            Shape::Square
        }
    };
    c.room.corridors = r.bool("env", "add_corridors");
    c.room.size_x = r.range("map_x");
    c.room.size_y = r.range("map_y");
    let unread = unread_keys(yaml, &r.read);
    r.problems.extend(unread);
    if r.problems.is_empty() {
        Ok(c)
    } else {
        Err(SimError::config(r.problems))
    }
}

/// Keys that SocNavGym's `v0.1` branch added to every config after 0.1.1: refused with that
/// reason, since socnav follows 0.1.1.
const LATER_KEYS: [(&str, &str); 2] = [
    ("episode", "end_with_collision"),
    ("env", "max_rotation_human"),
];

/// A problem for every section and key of `root` that 0.1.1 does not read.
fn unread_keys(root: &Value, read: &BTreeSet<(String, String)>) -> Vec<String> {
    let Some(sections) = root.as_object() else {
        return Vec::new();
    };
    let mut problems = Vec::new();
    for (section, keys) in sections {
        if !read.iter().any(|(s, _)| s == section) {
            problems.push(format!(
                "`{section}` is not a section of SocNavGym 0.1.1's config"
            ));
            continue;
        }
        let Some(keys) = keys.as_object() else {
            problems.push(format!(
                "SocNavGym `{section}` must be a mapping of keys, got {}",
                kind(keys)
            ));
            continue;
        };
        for key in keys.keys() {
            if read.contains(&(section.clone(), key.clone())) {
                continue;
            }
            if LATER_KEYS.contains(&(section.as_str(), key.as_str())) {
                problems.push(format!(
                    "`{section}.{key}` belongs to a later SocNavGym version (the v0.1 branch); \
                     socnav follows 0.1.1, which has no such key: remove it"
                ));
            } else {
                problems.push(format!(
                    "`{section}.{key}` is not a key of SocNavGym 0.1.1's config"
                ));
            }
        }
    }
    problems
}

/// A boolean as PyYAML (YAML 1.1, which 0.1.1 loads its configs with) reads one: its `true` and
/// `false` words, and also `yes`/`no`/`on`/`off` (lower case, capitalised or upper case), which
/// YAML 1.2 parsers leave as strings.
fn yaml11_bool(value: &Value) -> Option<bool> {
    match value {
        Value::Bool(b) => Some(*b),
        Value::String(s) => match s.as_str() {
            "yes" | "Yes" | "YES" | "on" | "On" | "ON" | "true" | "True" | "TRUE" => Some(true),
            "no" | "No" | "NO" | "off" | "Off" | "OFF" | "false" | "False" | "FALSE" => Some(false),
            _ => None,
        },
        _ => None,
    }
}

/// What kind of value `v` is, for messages.
fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "nothing",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "a mapping",
    }
}

/// A SocNavGym YAML file's text as the JSON value [`convert`] reads (the form the golden episodes'
/// headers carry), and a problem for each value JSON cannot hold (a NaN or an infinity, named by
/// its dotted key and left out as `null`); text that is not YAML is the error.
pub(super) fn parse_yaml(text: &str) -> Result<(Value, Vec<String>), SimError> {
    let docs = YamlLoader::load_from_str(text)
        .map_err(|e| SimError::config([format!("not valid YAML: {e}")]))?;
    let [doc] = docs.as_slice() else {
        return Err(SimError::config([format!(
            "a SocNavGym config is one YAML document, got {}",
            docs.len()
        )]));
    };
    let mut problems = Vec::new();
    let value = to_json(doc, "", &mut problems);
    Ok((value, problems))
}

/// `yaml` as JSON; `path` is its dotted key, for the problems.
fn to_json(yaml: &Yaml, path: &str, problems: &mut Vec<String>) -> Value {
    let named = |path: &str| {
        if path.is_empty() {
            "the document".to_owned()
        } else {
            format!("`{path}`")
        }
    };
    match yaml {
        Yaml::Null => Value::Null,
        Yaml::Boolean(b) => Value::Bool(*b),
        Yaml::Integer(i) => Value::Number((*i).into()),
        Yaml::String(s) => Value::String(s.clone()),
        Yaml::Real(text) => match yaml.as_f64().and_then(Number::from_f64) {
            Some(n) => Value::Number(n),
            None => {
                problems.push(format!(
                    "{} must be a finite number, got {text}",
                    named(path)
                ));
                Value::Null
            }
        },
        Yaml::Array(items) => Value::Array(
            items
                .iter()
                .enumerate()
                .map(|(i, item)| to_json(item, &format!("{path}[{i}]"), problems))
                .collect(),
        ),
        Yaml::Hash(entries) => {
            let mut map = Map::new();
            for (key, item) in entries {
                let key = match key {
                    Yaml::String(k) => k.clone(),
                    Yaml::Integer(i) => i.to_string(),
                    Yaml::Boolean(b) => b.to_string(),
                    other => {
                        problems.push(format!(
                            "{}: a key must be a name, got {other:?}",
                            named(path)
                        ));
                        continue;
                    }
                };
                let inner = if path.is_empty() {
                    key.clone()
                } else {
                    format!("{path}.{key}")
                };
                let item = to_json(item, &inner, problems);
                map.insert(key, item);
            }
            Value::Object(map)
        }
        Yaml::Alias(_) | Yaml::BadValue => {
            problems.push(format!("{}: an unresolved YAML alias", named(path)));
            Value::Null
        }
    }
}
