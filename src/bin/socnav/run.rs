//! `socnav run`: a batched rollout. Prints the outcome rates, the paper's metric means over the
//! finished episodes (docs/spec.md 8.3) and the throughput of the stepping alone (the policy's time
//! is not counted).

use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{Map, Value, json};
use socnav::episodes::Aggregate;
use socnav::episodes::TABLE_KEYS;
use socnav::spec::{EVENT_KEYS, N_EVENTS};
use socnav::{Actions, BatchEnv, Config, EnvOptions};

use crate::args::{BackendChoice, RunArgs};
use crate::policy::Policy;

/// Make a batch on the chosen backend (`auto` says on stderr when it falls back to the CPU).
pub fn make_env(
    config: Config,
    n_envs: usize,
    seed: u64,
    backend: BackendChoice,
    threads: Option<usize>,
) -> Result<BatchEnv, socnav::SimError> {
    BatchEnv::new(
        config,
        EnvOptions {
            n_envs,
            seed,
            threads,
            backend: backend.into(),
            ..Default::default()
        },
    )
}

pub fn run(a: &RunArgs) -> Result<(), Box<dyn std::error::Error>> {
    let config = Config::from_name_or_path(&a.config)?;
    let mut env = make_env(config, a.envs, a.seed, a.backend, a.threads)?;
    // The rollout reads the observations (the goal policy), the events and the statistics of
    // finished episodes: the GPU backend reads back no metrics or interactions.
    env.set_step_outputs(socnav::outputs::StepOutputs {
        events: true,
        ..socnav::outputs::StepOutputs::LEAN
    });
    env.reset(Some(a.seed))?;
    let mut policy = Policy::new(a.policy, a.seed, &env);
    let mut actions = vec![0.0f32; 3 * a.envs];
    let mut agg = Aggregate::default();
    let mut events = [0u64; N_EVENTS];
    let bar = progress_bar(a.steps as u64);
    let mut stepping = Duration::ZERO;
    for _ in 0..a.steps {
        policy.act(&env, &mut actions)?;
        let t = Instant::now();
        env.step(Actions::Continuous(&actions))?;
        stepping += t.elapsed();
        agg.add_finished(env.outputs());
        for row in env.outputs().events.chunks_exact(N_EVENTS) {
            for (total, &n) in events.iter_mut().zip(row) {
                *total += u64::from(n);
            }
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let env_steps = (a.envs * a.steps) as f64;
    let rate = env_steps / stepping.as_secs_f64();
    let summary = Summary {
        events: &events,
        a,
        env: &env,
        agg: &agg,
        rate,
        seconds: stepping.as_secs_f64(),
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&summary.json())?);
    } else {
        summary.print();
    }
    Ok(())
}

#[expect(
    clippy::expect_used,
    reason = "the template is a constant (and the bar runs in tests)"
)]
fn progress_bar(steps: u64) -> ProgressBar {
    // indicatif draws only when stderr is a terminal; in CI and pipes the bar stays silent.
    let bar = ProgressBar::new(steps);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} {wide_bar} {pos}/{len} steps  {per_sec}  eta {eta}",
        )
        .expect("valid progress template"),
    );
    bar
}

struct Summary<'a> {
    events: &'a [u64; N_EVENTS],
    a: &'a RunArgs,
    env: &'a BatchEnv,
    agg: &'a Aggregate,
    rate: f64,
    seconds: f64,
}

fn finite_or_null(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

impl Summary<'_> {
    fn json(&self) -> Value {
        let mut metrics = Map::new();
        for key in TABLE_KEYS {
            metrics.insert(
                key.to_string(),
                finite_or_null(self.agg.mean(key).unwrap_or(f64::NAN)),
            );
        }
        let m = |k: &str| finite_or_null(self.agg.mean(k).unwrap_or(f64::NAN));
        json!({
            "config": self.a.config,
            "backend": self.env.backend_name(),
            "device": self.env.device(),
            "threads": self.env.threads(),
            "envs": self.a.envs,
            "steps": self.a.steps,
            "seed": self.a.seed,
            "policy": format!("{:?}", self.a.policy).to_lowercase(),
            "env_steps": self.a.envs * self.a.steps,
            "seconds": self.seconds,
            "env_steps_per_s": self.rate,
            "episodes": self.agg.episodes(),
            "success_rate": m("success"),
            "collision_rate": m("collision"),
            "collision_human_rate": m("collision_human"),
            "collision_object_rate": m("collision_object"),
            "collision_wall_rate": m("collision_wall"),
            "timeout_rate": m("timeout"),
            "out_of_map_rate": m("out_of_map"),
            "mean_episode_length": m("length"),
            "metrics": metrics,
            "events": EVENT_KEYS.iter().zip(self.events).map(|(k, n)| (k.to_string(), json!(n))).collect::<Map<_, _>>(),
        })
    }

    fn print(&self) {
        let a = self.a;
        println!(
            "socnav run: {} | {} envs x {} steps | seed {} | {} backend on {} | {} policy",
            a.config,
            a.envs,
            a.steps,
            a.seed,
            self.env.backend_name(),
            self.env.device(),
            format!("{:?}", a.policy).to_lowercase()
        );
        if self.agg.episodes() == 0 {
            println!("episodes finished: none yet (run more steps for outcomes and metrics)");
        } else {
            self.print_outcomes();
        }
        println!(
            "throughput: {:.0} env-steps/s ({} env-steps in {:.2} s of stepping)",
            self.rate,
            a.envs * a.steps,
            self.seconds
        );
    }

    /// Outcome rates, social events and the metric table of the finished episodes.
    fn print_outcomes(&self) {
        let pct = |k: &str| 100.0 * self.agg.mean(k).unwrap_or(f64::NAN);
        println!(
            "episodes finished: {} (mean length {:.1} steps)",
            self.agg.episodes(),
            self.agg.mean("length").unwrap_or(f64::NAN)
        );
        println!(
            // As in 0.1.1, a wall collision is an object collision: the wall share is part of
            // the object share, not a third part.
            "outcomes: success {:.1} %, collision {:.1} % (human {:.1} %, object {:.1} %, of which walls {:.1} %), timeout {:.1} %, out of map {:.1} %",
            pct("success"),
            pct("collision"),
            pct("collision_human"),
            pct("collision_object"),
            pct("collision_wall"),
            pct("timeout"),
            pct("out_of_map")
        );
        if self.events.iter().any(|&n| n > 0) {
            let cells: Vec<String> = EVENT_KEYS
                .iter()
                .zip(self.events)
                .filter(|(_, n)| **n > 0)
                .map(|(k, n)| format!("{k} {n}"))
                .collect();
            println!("social events: {}", cells.join(", "));
        }
        println!("metrics (means over finished episodes, as the paper's table):");
        for chunk in TABLE_KEYS.chunks(4) {
            let cells: Vec<String> = chunk
                .iter()
                .map(|k| format!("{k:>26} {:>9.4}", self.agg.mean(k).unwrap_or(f64::NAN)))
                .collect();
            println!("{}", cells.join(""));
        }
    }
}
