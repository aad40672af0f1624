//! `socnav play`: drive the robot of one environment by hand in a live window (keyboard, or a
//! gamepad with the `gamepad` feature), in real time at the config's time step, with a heads-up
//! panel of the step, reward, outcome and the paper's metrics so far; `--record DIR` writes every
//! finished episode as SocNavGym 0.1.1's JSON recording plus socnav's sidecar (seed, config,
//! actions) from which `socnav.datasets` rebuilds it exactly.

use std::time::{Duration, Instant};

use socnav::recording::{RecordingDir, Step, episode_json};
use socnav::spec::{N_INFO, info};
use socnav::viewer::controls::{self, Held};
use socnav::viewer::{Command, Window, hud};
use socnav::{Actions, BatchEnv, Config, SimError};

use crate::args::PlayArgs;
use crate::outcome::outcome;

/// Fastest and slowest playback, relative to real time.
const SPEEDS: (f32, f32) = (1.0 / 16.0, 16.0);
/// How often the window is redrawn and the keys read (s).
const FRAME_S: f64 = 1.0 / 60.0;
/// Metrics of the paper's table shown while playing (their values so far in the episode).
const SHOWN: [(&str, usize); 8] = [
    ("path length (m)", info::PATH_LENGTH),
    ("closest human (m)", info::MINIMUM_DISTANCE_TO_HUMAN),
    ("personal space", info::PERSONAL_SPACE_COMPLIANCE),
    ("discomfort DSRNN", info::DISCOMFORT_DSRNN),
    ("discomfort SNGNN", info::DISCOMFORT_SNGNN),
    ("stalled time (s)", info::STALLED_TIME),
    ("velocity avg", info::V_AVG),
    ("closest obstacle", info::MINIMUM_OBSTACLE_DISTANCE),
];

/// The episode being played.
struct Episode {
    seed: u64,
    obs: Vec<f32>,
    actions: Vec<[f32; 3]>,
    discrete: Vec<u32>,
    rewards: Vec<f32>,
    trail: Vec<(f32, f32)>,
    ret: f64,
    outcome: Option<&'static str>,
}

impl Episode {
    fn start(env: &BatchEnv) -> Result<Self, SimError> {
        let s = env.state()?;
        Ok(Self {
            seed: s.episode_seed(0),
            obs: Vec::new(),
            actions: Vec::new(),
            discrete: Vec::new(),
            rewards: Vec::new(),
            trail: vec![(s.robot_x[0], s.robot_y[0])],
            ret: 0.0,
            outcome: None,
        })
    }
}

struct Player<'a> {
    args: &'a PlayArgs,
    env: BatchEnv,
    size: u32,
    holonomic: bool,
    speed: f32,
    paused: bool,
    episodes: usize,
    outcomes: Vec<&'static str>,
    record: Option<RecordingDir>,
    written: usize,
}

impl Player<'_> {
    /// Step once with the action of the keys `held` or, when a gamepad's sticks are pushed,
    /// theirs; finishes the episode when it ends.
    fn step(
        &mut self,
        ep: &mut Episode,
        held: Held,
        sticks: Option<controls::Sticks>,
    ) -> Result<(), Box<dyn std::error::Error>> {
        let pad = sticks
            .map(|s| controls::gamepad_action(s, controls::DEAD_ZONE, self.holonomic))
            .filter(|a| a.iter().any(|&v| v != 0.0));
        let (action, discrete) = match (self.args.discrete, pad) {
            (true, _) => {
                let d = controls::keyboard_discrete(pad.map_or(held, controls::held_of));
                (controls::discrete_to_continuous(d), Some(d))
            }
            (false, Some(a)) => (a, None),
            (false, None) => (controls::keyboard_action(held, self.holonomic), None),
        };
        match discrete {
            Some(d) => self.env.step(Actions::Discrete(&[d]))?,
            None => self.env.step(Actions::Continuous(&action))?,
        }
        let out = self.env.outputs();
        let dim = self.env.layout().dim;
        ep.obs.extend_from_slice(&out.obs[..dim]);
        ep.actions.push(action);
        ep.discrete.extend(discrete);
        ep.rewards.push(out.reward[0]);
        ep.ret += f64::from(out.reward[0]);
        let s = self.env.state()?;
        ep.trail.push((s.robot_x[0], s.robot_y[0]));
        if out.terminated[0] != 0 || out.truncated[0] != 0 {
            let ended = outcome(&out.info[..N_INFO]);
            ep.outcome = Some(ended);
            self.outcomes.push(ended);
            self.episodes += 1;
            self.write(ep)?;
        }
        Ok(())
    }

    fn write(&mut self, ep: &Episode) -> Result<(), Box<dyn std::error::Error>> {
        let Some(dir) = self.record.as_mut() else {
            return Ok(());
        };
        let layout = *self.env.layout();
        let steps: Vec<Step<'_>> = ep
            .obs
            .chunks_exact(layout.dim)
            .zip(&ep.actions)
            .zip(&ep.rewards)
            .map(|((obs, &action), &reward)| Step {
                obs,
                action,
                reward,
            })
            .collect();
        let json = episode_json(&layout, &steps)?;
        let actions = if self.args.discrete {
            serde_json::json!(ep.discrete)
        } else {
            serde_json::json!(ep.actions)
        };
        let sidecar = serde_json::json!({
            "format": "socnav-played/1",
            "config": recorded_config(&self.args.config),
            "seed": ep.seed,
            "action_type": if self.args.discrete { "discrete" } else { "continuous" },
            "actions": actions,
            "steps": ep.actions.len(),
            "outcome": ep.outcome,
        });
        let path = dir.write(&json, Some(&sidecar.to_string()))?;
        self.written += 1;
        eprintln!(
            "socnav play: episode {} ({}) -> {}",
            ep.seed,
            ep.outcome.unwrap_or("?"),
            path.display()
        );
        Ok(())
    }

    fn lines(&self, ep: &Episode, action: [f32; 3]) -> Vec<String> {
        let out = self.env.outputs();
        let row = &out.info[..N_INFO];
        let p = self.env.params();
        let mut lines = vec![
            format!("socnav play  {}", self.args.config),
            format!("episode seed {}", ep.seed),
            format!(
                "step {}/{}  speed x{}{}",
                ep.actions.len(),
                p.episode_length + 1,
                speed_text(self.speed),
                if self.paused { "  PAUSED" } else { "" }
            ),
            String::new(),
            format!(
                "action fwd {:+.2} lat {:+.2} rot {:+.2}",
                action[0], action[1], action[2]
            ),
            format!(
                "reward {:+.4}  return {:+.3}",
                ep.rewards.last().copied().unwrap_or(0.0),
                ep.ret
            ),
            format!(
                "  distance {:+.4}  alive {:+.4}",
                row[info::DISTANCE_REWARD],
                row[info::ALIVE_REWARD]
            ),
            format!("  sngnn {:+.4}", row[info::SNGNN_REWARD]),
            String::new(),
        ];
        if let Some(o) = ep.outcome {
            lines.push(format!("{}{o}", hud::ACCENT_MARK));
            lines.push(format!("{}R: next episode, Esc: quit", hud::ACCENT_MARK));
            lines.push(String::new());
        }
        lines.push("metrics so far".into());
        for (name, k) in SHOWN {
            lines.push(format!("  {name:<18} {:.3}", row[k]));
        }
        lines.push(String::new());
        lines.push(format!(
            "episodes {}  recorded {}",
            self.episodes, self.written
        ));
        lines.push(String::new());
        lines.push("arrows/WASD drive, Q/E strafe".into());
        lines.push("space pause, N step, +/- speed".into());
        lines.push("R restart, Esc quit".into());
        lines
    }
}

/// The gamepads when the `gamepad` feature is built (none otherwise).
struct Gamepads {
    #[cfg(feature = "gamepad")]
    pads: Option<socnav::viewer::gamepad::Pads>,
}

impl Gamepads {
    fn open() -> Self {
        #[cfg(feature = "gamepad")]
        {
            let pads = socnav::viewer::gamepad::Pads::open()
                .map_err(|e| eprintln!("socnav play: {e}; driving by keyboard"))
                .ok();
            Self { pads }
        }
        #[cfg(not(feature = "gamepad"))]
        Self {}
    }

    /// The first pad's sticks (None without one) and its commands.
    #[cfg_attr(
        not(feature = "gamepad"),
        expect(clippy::unused_self, reason = "the same call with or without gamepads")
    )]
    fn poll(&mut self) -> (Option<controls::Sticks>, Vec<Command>) {
        #[cfg(feature = "gamepad")]
        if let Some(p) = self.pads.as_mut() {
            let input = p.poll();
            return (input.sticks, input.commands);
        }
        (None, Vec::new())
    }
}

/// The config as a recording names it: a file by its absolute path (so the recording replays
/// from anywhere), a shipped config by its name.
fn recorded_config(config: &str) -> String {
    std::fs::canonicalize(config).map_or_else(|_| config.to_owned(), |p| p.display().to_string())
}

fn speed_text(speed: f32) -> String {
    if speed >= 1.0 {
        format!("{speed}")
    } else {
        format!("1/{}", (1.0 / speed).round())
    }
}

pub fn play(a: &PlayArgs) -> Result<(), Box<dyn std::error::Error>> {
    if !(SPEEDS.0..=SPEEDS.1).contains(&a.speed) {
        return Err(format!(
            "--speed {}: give a number from 1/16 to 16 (1 is real time)",
            a.speed
        )
        .into());
    }
    let config = Config::from_name_or_path(&a.config)?;
    let size = a.size.unwrap_or(config.render.resolution);
    let env = BatchEnv::single(config, a.seed)?;
    let holonomic = env.params().holonomic != 0;
    let record = a.record.as_deref().map(RecordingDir::open).transpose()?;
    let mut player = Player {
        args: a,
        env,
        size,
        holonomic,
        speed: a.speed,
        paused: false,
        episodes: 0,
        outcomes: Vec::new(),
        record,
        written: 0,
    };
    let mut ep = Episode::start(&player.env)?;
    let first = socnav::render::draw(player.env.params(), player.env.state()?, 0, &ep.trail, size)?;
    let lines = player.lines(&ep, [0.0; 3]);
    let dims = hud::size(
        first.width() as usize,
        first.height() as usize,
        lines.len() + 4,
    );
    let mut window = Window::open("socnav play", dims.0, dims.1)?;
    let dt = f64::from(player.env.params().dt);
    let mut due = Instant::now();
    let mut pixels = Vec::new();
    let mut last_action = [0.0f32; 3];
    let mut pads = Gamepads::open();
    'frames: while window.is_open() {
        let frame_start = Instant::now();
        let input = window.poll();
        let (sticks, pad_commands) = pads.poll();
        let mut single = false;
        for c in input.commands.into_iter().chain(pad_commands) {
            match c {
                Command::Quit => break 'frames,
                Command::Restart => {
                    player.env.reset(None)?;
                    ep = Episode::start(&player.env)?;
                    due = Instant::now();
                }
                Command::Pause => player.paused = !player.paused,
                Command::Step => single = true,
                Command::Faster => player.speed = (player.speed * 2.0).min(SPEEDS.1),
                Command::Slower => player.speed = (player.speed / 2.0).max(SPEEDS.0),
            }
        }
        let now = Instant::now();
        if ep.outcome.is_none() && ((!player.paused && now >= due) || single) {
            player.step(&mut ep, input.held, sticks)?;
            last_action = *ep.actions.last().unwrap_or(&[0.0; 3]);
            let period = Duration::from_secs_f64(dt / f64::from(player.speed));
            // Behind by more than a step (a slow frame): start counting again from now.
            due = if now > due + period {
                now + period
            } else {
                due + period
            };
            if ep.outcome.is_some() && a.episodes.is_some_and(|n| player.episodes >= n) {
                break 'frames;
            }
        }
        let scene = socnav::render::draw(
            player.env.params(),
            player.env.state()?,
            0,
            &ep.trail,
            player.size,
        )?;
        hud::compose(
            &scene,
            &player.lines(&ep, last_action),
            window.size(),
            &mut pixels,
        );
        window.show(&pixels)?;
        let spent = frame_start.elapsed().as_secs_f64();
        if spent < FRAME_S {
            std::thread::sleep(Duration::from_secs_f64(FRAME_S - spent));
        }
    }
    summary(&player);
    Ok(())
}

fn summary(p: &Player<'_>) {
    let mut counts: Vec<(&str, usize)> = Vec::new();
    for o in &p.outcomes {
        match counts.iter_mut().find(|(k, _)| k == o) {
            Some((_, n)) => *n += 1,
            None => counts.push((o, 1)),
        }
    }
    let outcomes: Vec<String> = counts.iter().map(|(k, n)| format!("{n} {k}")).collect();
    println!(
        "socnav play: {} episodes ({}), {} recorded",
        p.episodes,
        if outcomes.is_empty() {
            "none finished".into()
        } else {
            outcomes.join(", ")
        },
        p.written
    );
}
