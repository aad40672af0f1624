//! Reading the golden SocNavGym 0.1.1 episodes and comparing socnav's step with them.

#![allow(
    dead_code,
    unused_imports,
    reason = "the suite and golden_replay each use a different part of this module"
)]

mod compare;
mod conditioning;
mod contact;
mod corrected;
mod rvo2;

use std::io::Read;
use std::path::{Path, PathBuf};

use serde_json::{Value, json};
use socnav::config::{ContactShape, RewardKind};
use socnav::{Actions, BatchEnv, Config, EnvOptions};

pub use compare::{Report, minimum_distance_to_human, with_flipped_from};
pub use conditioning::{direction_error, extent, rvo2_velocity_error, ulp};
pub use corrected::{
    Outcome, Perturbation, time_to_collision, time_to_collision_outcomes,
    time_to_collision_possible,
};
pub use rvo2::{Problem, Who, problem, problems};

/// The published golden episodes, in the repository (`tests/data/golden/socnavgym`): tests that
/// check specific published files (SNGNN graph dumps, hand-built scenes) read these.
pub fn published_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/golden/socnavgym")
}

/// The golden directory the replay and the tests over every episode read: `SOCNAV_GOLDEN_DIR`,
/// else [`published_dir`].
pub fn golden_dir() -> PathBuf {
    std::env::var_os("SOCNAV_GOLDEN_DIR")
        .filter(|d| !d.is_empty())
        .map_or_else(published_dir, PathBuf::from)
}

/// [`golden_dir`] when it exists; otherwise `None`, after a `SKIP` line naming `test` and the
/// missing folder (a `SOCNAV_GOLDEN_DIR` that points nowhere skips, it does not fail).
pub fn golden_dir_or_skip(test: &str) -> Option<PathBuf> {
    let dir = golden_dir();
    if dir.is_dir() {
        return Some(dir);
    }
    crate::common::skip::skip(
        None,
        &format!(
            "{test}: no golden episodes at {} (SOCNAV_GOLDEN_DIR)",
            dir.display()
        ),
    );
    None
}

/// One recorded episode.
pub struct Episode {
    root: Value,
}

/// One recorded step.
#[derive(Clone, Copy)]
pub struct Step<'a> {
    pub v: &'a Value,
}

/// Every `*.json.gz` episode of `dir` whose file name starts with `filter`, sorted by name.
pub fn load_episodes(dir: &Path, filter: Option<&str>) -> Vec<(String, Episode)> {
    let entries = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot read golden dir {}: {e}", dir.display()));
    let mut names: Vec<String> = entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".json.gz") && filter.is_none_or(|f| n.starts_with(f)))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|n| {
            let ep = Episode::load(&dir.join(&n));
            (n.trim_end_matches(".json.gz").to_string(), ep)
        })
        .collect()
}

impl Episode {
    pub fn load(path: &Path) -> Self {
        let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut text = String::new();
        flate2::read::GzDecoder::new(file)
            .read_to_string(&mut text)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let root =
            serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        Self { root }
    }

    pub fn header(&self) -> &Value {
        &self.root["header"]
    }

    pub fn config_name(&self) -> String {
        self.header()["config_name"]
            .as_str()
            .expect("header.config_name")
            .to_string()
    }

    /// The recorded step whose tick is `t`, to edit (synthetic golden steps).
    pub fn step_mut(&mut self, t: u64) -> &mut Value {
        self.root["steps"]
            .as_array_mut()
            .expect("steps")
            .iter_mut()
            .find(|s| s["t"] == t)
            .unwrap_or_else(|| panic!("no step {t}"))
    }

    pub fn initial_state(&self) -> &Value {
        &self.root["initial"]["state"]
    }

    pub fn initial_obs(&self) -> &Value {
        &self.root["initial"]["obs"]
    }

    pub fn steps(&self) -> impl Iterator<Item = Step<'_>> {
        self.root["steps"]
            .as_array()
            .expect("steps")
            .iter()
            .map(|v| Step { v })
    }

    /// The state document socnav loads: the header's static part plus a snapshot.
    /// The document that starts `step` from `state`, with the group noise the step drew (golden
    /// README section 8: injected so that group motion replays exactly).
    pub fn step_document(&self, state: &Value, step: &Step<'_>) -> Value {
        let mut state = state.clone();
        if let Some(noise) = step.v.get("group_noise") {
            state["group_noise"] = noise.clone();
        }
        self.document(&state)
    }

    pub fn document(&self, state: &Value) -> Value {
        let h = self.header();
        json!({
            "room": h["room"], "walls": h["walls"], "spawn_blockers": h["spawn_blockers"],
            "human_params": h["human_params"], "counts": h["counts"], "state": state,
        })
    }
}

impl<'a> Step<'a> {
    pub fn action(&self) -> Vec<f32> {
        self.v["action"]
            .as_array()
            .expect("action")
            .iter()
            .map(|x| x.as_f64().expect("action value") as f32)
            .collect()
    }

    pub fn state(&self) -> &'a Value {
        &self.v["state"]
    }

    /// The state the step's outputs describe (before the after-observation events).
    /// The SNGNN-v2 frame 0.1.1 recorded at this step, as a state document's `sngnn_frames`
    /// entry: its `sngnn.frame` plus the tick and the robot pose it was taken from (`None` on
    /// a terminal step, which records no frame).
    pub fn sngnn_frame(&self) -> Option<Value> {
        let frame = self.v.get("sngnn")?.get("frame")?;
        let mut frame = frame.clone();
        let robot = &self.state_after_motion()["robot"];
        frame["tick"] = json!(self.t());
        frame["robot"] = json!({"x": robot["x"], "y": robot["y"], "theta": robot["theta"]});
        Some(frame)
    }

    pub fn state_after_motion(&self) -> &'a Value {
        self.v
            .get("state_before_events")
            .unwrap_or(&self.v["state"])
    }

    pub fn replayable(&self) -> bool {
        self.v["outputs_replayable"].as_bool().unwrap_or(true)
    }

    pub fn t(&self) -> u64 {
        self.v["t"].as_u64().expect("t")
    }

    /// Ids of humans (and group indices) whose goals were re-sampled during the step.
    pub fn resampled(&self) -> (Vec<u64>, Vec<u64>) {
        let mut humans = Vec::new();
        let mut groups = Vec::new();
        for ev in self.v["events"].as_array().into_iter().flatten() {
            match ev["type"].as_str() {
                Some("goal_resample") => humans.extend(ev["human"].as_u64().or(ev["id"].as_u64())),
                Some("group_goal_resample") => groups.extend(ev["group_index"].as_u64()),
                _ => {}
            }
        }
        (humans, groups)
    }
}

/// The socnav config of an episode: `configs/<stem>.toml` for its `config_name`, which must equal
/// the header's YAML values.
pub fn config_for(ep: &Episode) -> Result<Config, String> {
    let name = ep.config_name();
    let stem = name
        .replace("_no_sngnn", "")
        .replace("_with_sngnn", "_sngnn");
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(format!("{stem}.toml"));
    let ours = Config::from_file(&path).map_err(|e| e.to_string())?;
    let theirs = Config::from_socnavgym(&ep.header()["config"]).map_err(|e| e.to_string())?;
    if ours != theirs {
        return Err(format!(
            "configs/{stem}.toml differs from the golden header's config:\nours:   {ours:?}\ntheirs: {theirs:?}"
        ));
    }
    Ok(ours)
}

/// A batch of one environment that replays `ep` (`name` in messages): its config with contacts
/// decided as `shape` says, in replay mode (socnav's own social events off), and the report its
/// steps are compared into.
pub fn replay_env(ep: &Episode, name: &str, shape: ContactShape) -> (BatchEnv, Report) {
    let mut config = config_for(ep).unwrap_or_else(|e| panic!("{name}: {e}"));
    config.model.contact_shape = shape;
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs: 1,
            seed: 0,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    env.set_replay(true);
    let report = Report::new(name).with_contact_shape(shape, env.params().human_radius as f64);
    (env, report)
}

/// Replay episode `ep` (`name` in messages) step by step, as the golden replay does: load the
/// recorded state before each step with `set_state`, take the recorded action, compare the step
/// with the recording (contacts decided as `shape` says).
pub fn replay_episode(name: &str, ep: &Episode, shape: ContactShape) -> Report {
    let (mut env, mut report) = replay_env(ep, name, shape);
    env.set_state(0, &ep.document(ep.initial_state()))
        .unwrap_or_else(|e| panic!("{name}: set_state: {e}"));
    report.compare_obs(&env, ep.initial_obs(), &[], &[], "initial");
    let mut prev = ep.initial_state();
    // SNGNN-v2 episodes: 0.1.1's frames of the earlier steps, newest first.
    let mut frames: Vec<Value> = Vec::new();
    for step in ep.steps() {
        let mut doc = ep.step_document(prev, &step);
        if env.config().reward.kind == RewardKind::Sngnn {
            doc["state"]["sngnn_frames"] = Value::Array(frames.clone());
        }
        env.set_state(0, &doc)
            .unwrap_or_else(|e| panic!("{name}: set_state: {e}"));
        env.step(Actions::Continuous(&step.action()))
            .unwrap_or_else(|e| panic!("{name}: step: {e}"));
        report.compare_step(&env, ep, step, prev);
        if let Some(frame) = step.sngnn_frame() {
            frames.insert(0, frame);
        }
        prev = step.state();
    }
    report
}

/// The single reference episodes kept beside the golden ones (`tests/data/fixtures`, its
/// `README.md`).
pub fn fixtures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fixtures")
}

/// A golden number: JSON number, "inf"/"-inf"/"nan", null (None → NaN) or bool.
pub fn num(v: &Value) -> f64 {
    match v {
        Value::Number(n) => n.as_f64().expect("number"),
        Value::String(s) if s == "inf" => f64::INFINITY,
        Value::String(s) if s == "-inf" => f64::NEG_INFINITY,
        Value::Bool(b) => f64::from(u8::from(*b)),
        _ => f64::NAN,
    }
}
