//! `socnav soak`: step configs for a long time with adversarial actions, checking after every
//! step that every output is finite (the info values the spec defines as NaN or +inf excepted)
//! and that the state keeps its invariants (`socnav::state::invariants`), sampling the process's
//! memory. The progress (steps, counts of NaN, broken invariants and panics, memory samples) is
//! written to a JSON file after every chunk, and a run with the same file resumes where it
//! stopped, so a billion steps can proceed in chunks.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::Instant;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde_json::{Value, json};
use socnav::config::Kinematics;
use socnav::spec::{N_INFO, info_outside_spec};
use socnav::state::invariants::violations;
use socnav::{Actions, BatchEnv, Config, SimError};

use crate::args::SoakArgs;
use crate::run::make_env;

/// Kinds of adversarial actions, one per environment by index (and rotated every chunk).
const KINDS: usize = 4;

/// Per-config totals, as the progress file holds them.
#[derive(Debug, Default, Clone, Copy)]
struct Tally {
    steps: u64,
    non_finite: u64,
    broken: u64,
    panics: u64,
}

impl Tally {
    fn to_json(self) -> Value {
        json!({"env_steps": self.steps, "non_finite": self.non_finite, "broken_invariants": self.broken, "panics": self.panics})
    }

    /// The tally a record holds (zeros for a config it does not name), or the key that is not
    /// a count.
    fn from_json(v: &Value) -> Result<Self, &'static str> {
        let get = |k: &'static str| match &v[k] {
            Value::Null => Ok(0),
            other => other.as_u64().ok_or(k),
        };
        Ok(Self {
            steps: get("env_steps")?,
            non_finite: get("non_finite")?,
            broken: get("broken_invariants")?,
            panics: get("panics")?,
        })
    }
}

/// Resident memory of this process (MB), from /proc (Linux); None elsewhere.
fn rss_mb() -> Option<f64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: f64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096.0 / 1e6)
}

/// Fill `actions` for one batch step: environment `e` gets kind `(e + rotation) % KINDS`:
/// bang-bang (full forward or back, full turn, flipping), spinning in place, uniform random,
/// or the go-to-goal controller.
fn adversarial(env: &BatchEnv, rng: &mut StdRng, tick: u64, rotation: usize, actions: &mut [f32]) {
    let holonomic = env.config().robot.kinematics == Kinematics::Holonomic;
    socnav::policies::goal_actions(env, actions);
    for (e, a) in actions.chunks_exact_mut(3).enumerate() {
        let flip = |period: u64| {
            if (tick / period).is_multiple_of(2) {
                1.0
            } else {
                -1.0
            }
        };
        match (e + rotation) % KINDS {
            0 => a.copy_from_slice(&[flip(5), if holonomic { flip(3) } else { 0.0 }, flip(2)]),
            1 => a.copy_from_slice(&[0.0, 0.0, 1.0]),
            2 => {
                a[0] = rng.random_range(-1.0..=1.0);
                a[1] = if holonomic {
                    rng.random_range(-1.0..=1.0)
                } else {
                    0.0
                };
                a[2] = rng.random_range(-1.0..=1.0);
            }
            _ => {} // the goal controller's action, already there
        }
    }
}

/// Non-finite output values of environment `e` this step, beyond the info values the spec defines
/// so (`info_outside_spec`; the state is read only when an info value is non-finite, since on the
/// GPU backend reading it is a download).
fn non_finite(env: &BatchEnv, e: usize) -> Result<u64, SimError> {
    let out = env.outputs();
    let dim = env.layout().dim;
    let obs = out.obs[e * dim..(e + 1) * dim]
        .iter()
        .filter(|v| !v.is_finite())
        .count();
    let info_row = &out.info[e * N_INFO..(e + 1) * N_INFO];
    let reward = usize::from(!out.reward[e].is_finite());
    let infos = if info_row.iter().all(|v| v.is_finite()) {
        0
    } else {
        info_outside_spec(env.state()?, e, info_row).len()
    };
    Ok((obs + infos + reward) as u64)
}

/// The format tag of a soak record.
const FORMAT: &str = "socnav-soak/1";

/// The record at `path` to resume, or an empty one where there is no file. Anything but a soak
/// record (another program's JSON, a record of another format, or of another batch: `envs` and
/// `backend`, since a resumed run adds to its tallies) is refused, so that the run never
/// overwrites it.
fn load(path: &Path, a: &SoakArgs) -> Result<Value, String> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(json!({})),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    let refuse = |why: String| {
        format!(
            "{}: not a soak record to resume ({why}); give another --record",
            path.display()
        )
    };
    let record: Value = serde_json::from_str(&text).map_err(|e| refuse(e.to_string()))?;
    if record["format"] != FORMAT {
        return Err(refuse(format!(
            "its format is {}, not \"{FORMAT}\"",
            record["format"]
        )));
    }
    if let Some(configs) = record["configs"].as_object() {
        for (name, tally) in configs {
            Tally::from_json(tally)
                .map_err(|key| refuse(format!("`configs.{name}.{key}` is not a count")))?;
        }
    } else {
        return Err(refuse("`configs` is not an object".into()));
    }
    let backend = backend_name(a);
    if record["envs"] != a.envs || record["backend"] != backend.as_str() {
        return Err(refuse(format!(
            "it was made with --envs {} --backend {}, this run asks for --envs {} --backend {backend}",
            record["envs"], record["backend"], a.envs
        )));
    }
    Ok(record)
}

/// The backend as the record names it.
fn backend_name(a: &SoakArgs) -> String {
    format!("{:?}", a.backend).to_lowercase()
}

/// Write `record` to `path` through a temporary file beside it (named after it and this
/// process, so that it replaces nothing of the user's), renamed over it when whole.
fn save(path: &Path, record: &Value) -> Result<(), String> {
    let name = path
        .file_name()
        .map_or_else(|| "soak".into(), |n| n.to_string_lossy());
    let part = path.with_file_name(format!(".{name}.{}.part", std::process::id()));
    let text = serde_json::to_string_pretty(record).map_err(|e| e.to_string())?;
    std::fs::write(&part, text)
        .and_then(|()| std::fs::rename(&part, path))
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

pub fn soak(a: &SoakArgs) -> Result<(), Box<dyn std::error::Error>> {
    let configs: Vec<String> = a
        .configs
        .split(',')
        .map(str::trim)
        .filter(|c| !c.is_empty())
        .map(String::from)
        .collect();
    if configs.is_empty() {
        return Err("--configs names no config".into());
    }
    let mut record = load(&a.record, a)?;
    let mut tallies: Vec<Tally> = configs
        .iter()
        .map(|c| Tally::from_json(&record["configs"][c]).unwrap_or_default())
        .collect();
    // Memory samples as [env-steps so far, MB, run]: each run (process) is numbered, since
    // growth only means something within one process.
    let mut rss: Vec<Value> = record["rss_mb"].as_array().cloned().unwrap_or_default();
    let run = rss
        .iter()
        .filter_map(|v| v[2].as_u64())
        .max()
        .map_or(0, |r| r + 1);
    let wall_before = record["wall_s"].as_f64().unwrap_or(0.0);
    let steps_before: u64 = tallies.iter().map(|t| t.steps).sum();
    // Configs of the record that this run does not step keep their tallies.
    let mut others = record["configs"].as_object().cloned().unwrap_or_default();
    others.retain(|name, _| !configs.contains(name));
    let mut envs = Vec::with_capacity(configs.len());
    for (k, name) in configs.iter().enumerate() {
        let config = Config::from_name_or_path(name)?;
        // Each resumed chunk plays new episodes: the seed moves with the steps already done.
        let seed = a.seed ^ tallies[k].steps.rotate_left(17) ^ k as u64;
        let mut env = make_env(config, a.envs, seed, a.backend, a.threads)?;
        env.reset(Some(seed))?;
        envs.push(env);
    }
    let start = Instant::now();
    let mut rng = StdRng::seed_from_u64(a.seed ^ 0x50a4);
    let mut actions = vec![0.0f32; 3 * a.envs];
    let per_config = a.steps;
    let mut chunk = 0usize;
    while tallies.iter().any(|t| t.steps < per_config) {
        for (k, env) in envs.iter_mut().enumerate() {
            if tallies[k].steps >= per_config {
                continue;
            }
            let remaining = per_config - tallies[k].steps;
            let batch_steps = (a.chunk.min(remaining) / a.envs as u64).max(1);
            for tick in 0..batch_steps {
                adversarial(env, &mut rng, tick, chunk, &mut actions);
                let stepped =
                    catch_unwind(AssertUnwindSafe(|| env.step(Actions::Continuous(&actions))));
                match stepped {
                    Ok(result) => result?,
                    Err(_) => {
                        tallies[k].panics += 1;
                        continue;
                    }
                }
                let t = &mut tallies[k];
                t.steps += a.envs as u64;
                for e in 0..a.envs {
                    t.non_finite += non_finite(env, e)?;
                    if tick.is_multiple_of(a.check_every) {
                        let broken = violations(env.state()?, e);
                        if let Some(first) = broken.first() {
                            if t.broken == 0 {
                                eprintln!("socnav soak: {}: {first}", configs[k]);
                            }
                            t.broken += broken.len() as u64;
                        }
                    }
                }
            }
        }
        chunk += 1;
        let total: u64 = tallies.iter().map(|t| t.steps).sum();
        if let Some(mb) = rss_mb() {
            rss.push(json!([total, mb, run]));
        }
        let wall = wall_before + start.elapsed().as_secs_f64();
        record = json!({
            "format": FORMAT,
            "envs": a.envs,
            "backend": backend_name(a),
            "steps_per_config": per_config,
            "configs": others
                .clone()
                .into_iter()
                .chain(configs.iter().zip(&tallies).map(|(c, t)| (c.clone(), t.to_json())))
                .collect::<serde_json::Map<_, _>>(),
            "rss_mb": rss,
            "wall_s": wall,
        });
        save(&a.record, &record)?;
        let bad: u64 = tallies
            .iter()
            .map(|t| t.non_finite + t.broken + t.panics)
            .sum();
        let this_run = start.elapsed().as_secs_f64();
        eprintln!(
            "socnav soak: {:.3e} env-steps in {wall:.0} s ({:.0} env-steps/s in this run), {bad} problems, RSS {:.0} MB",
            total as f64,
            (total - steps_before) as f64 / this_run.max(1e-9),
            rss_mb().unwrap_or(f64::NAN)
        );
    }
    summary(&configs, &tallies, &rss, run);
    let bad: u64 = tallies
        .iter()
        .map(|t| t.non_finite + t.broken + t.panics)
        .sum();
    if bad > 0 {
        return Err(format!(
            "{bad} problems (non-finite outputs, broken invariants, panics); see {}",
            a.record.display()
        )
        .into());
    }
    Ok(())
}

fn summary(configs: &[String], tallies: &[Tally], rss: &[Value], run: u64) {
    for (c, t) in configs.iter().zip(tallies) {
        println!(
            "{c:<16} {:>14} env-steps  non-finite {}  broken invariants {}  panics {}",
            t.steps, t.non_finite, t.broken, t.panics
        );
    }
    // Memory growth after warm-up in this run: from the first tenth of its samples to the last.
    let mb: Vec<f64> = rss
        .iter()
        .filter(|v| v[2].as_u64() == Some(run))
        .filter_map(|v| v[1].as_f64())
        .collect();
    if mb.len() >= 2 {
        let warm = mb[mb.len() / 10];
        let last = mb[mb.len() - 1];
        println!(
            "RSS {warm:.0} MB after warm-up, {last:.0} MB at the end ({:+.2} %)",
            100.0 * (last / warm - 1.0)
        );
    }
}
