//! Command-line arguments.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// GPU-batched social-navigation simulator (SocNavGym 0.1.1 semantics).
#[derive(Debug, Parser)]
#[command(name = "socnav", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Roll out a batch of environments and print outcome rates, metrics and throughput.
    Run(RunArgs),
    /// Measure env-steps/s, in total and per stage, over a table of batch sizes.
    Bench(BenchArgs),
    /// Validate a config and print it with every default resolved.
    CheckConfig(CheckArgs),
    /// Draw an episode to an animated GIF (or its first frame to a PNG).
    Render(RenderArgs),
    /// Draw the discomfort around people in one scene: SNGNN-v2 and DSRNN with the robot placed
    /// at every point of a grid (PNG).
    Heatmap(HeatmapArgs),
    /// Step configs for a long time with adversarial actions, checking every output and the
    /// state's invariants after every step, and sampling memory; resumable.
    Soak(SoakArgs),
    /// Drive the robot by hand in a live window (keyboard; gamepad with the `gamepad` feature),
    /// optionally recording every episode.
    Play(PlayArgs),
    /// List the GPU adapters wgpu finds and which one each backend choice would take.
    Devices,
    /// The SNGNN-v2 reward's weights (GPL-3.0, not shipped): install them, show where they are.
    #[command(subcommand)]
    Sngnn(SngnnCommand),
}

#[derive(Debug, Subcommand)]
pub enum SngnnCommand {
    /// Download the socnavgym 0.1.1 wheel with pip, copy SOCNAV_V2.tch out of it into the
    /// cache and check it. The interpreter is `$SOCNAV_PYTHON`, else `python3`. Exit status 3
    /// when the download fails (no pip, no network).
    Install(InstallArgs),
    /// Print the weight file socnav would load (first line), the rule that chose it and whether
    /// it exists.
    Path(PathArgs),
}

#[derive(Debug, Args)]
pub struct InstallArgs {
    /// Cache directory (default: $SOCNAV_CACHE_DIR, else $XDG_CACHE_HOME/socnav, else
    /// ~/.cache/socnav); the file goes to `sngnn/SOCNAV_V2.tch` below it.
    #[arg(long)]
    pub cache_dir: Option<PathBuf>,
    /// Download and replace the file even when a valid one is installed.
    #[arg(long)]
    pub force: bool,
}

#[derive(Debug, Args)]
pub struct PathArgs {
    /// Config whose `reward.sngnn_weights` takes part (a shipped name or a TOML or SocNavGym YAML path).
    #[arg(long)]
    pub config: Option<String>,
}

/// Which backend runs the batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BackendChoice {
    /// A hardware GPU when one exists, else the CPU.
    Auto,
    /// The CPU backend.
    Cpu,
    /// The GPU backend, on any adapter (software ones included).
    Gpu,
}

impl From<BackendChoice> for socnav::backend::BackendChoice {
    fn from(c: BackendChoice) -> Self {
        match c {
            BackendChoice::Auto => Self::Auto,
            BackendChoice::Cpu => Self::Cpu,
            BackendChoice::Gpu => Self::Gpu,
        }
    }
}

/// Which optional per-step outputs a step delivers (`socnav::outputs::StepOutputs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StepOutputsChoice {
    /// Every output column (`BatchEnv`'s default).
    All,
    /// What Python's `make_vec` hands out: the metrics (`info`), no interactions or events.
    Vector,
    /// Only the observation, its counts, reward and flags (`make_vec(step_info=False)`).
    Lean,
}

impl From<StepOutputsChoice> for socnav::outputs::StepOutputs {
    fn from(c: StepOutputsChoice) -> Self {
        match c {
            StepOutputsChoice::All => Self::ALL,
            StepOutputsChoice::Vector => Self {
                info: true,
                ..Self::LEAN
            },
            StepOutputsChoice::Lean => Self::LEAN,
        }
    }
}

/// A hardware path of the GPU backend that `socnav bench --lane-paths` turns back into a
/// software adapter's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LanePath {
    /// The observation written into its rows in place, not staged through workgroup memory.
    Staging,
    /// Each reset on one lane, not a workgroup's.
    Resets,
    /// Each environment of `formation` and `social_events`, its regroupings included, on one
    /// lane, not a workgroup's.
    Regroups,
    /// Each ORCA obstacle rebuild over the scratch buffer, not in workgroup memory.
    Obstacles,
    /// The observation's entity records in the observing lane, not a lane each.
    Records,
    /// Each reset's ORCA obstacles built on the host, in its reset-pool row, not rebuilt on the
    /// device after the reset.
    ResetObstacles,
    /// The readback's other pieces and the queued obstacle rebuilds submitted after the host's
    /// work that overlaps the step's passes, not right after the step's submit.
    ReadbackAfterHostWork,
}

/// How actions are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PolicyChoice {
    /// Uniform random actions in [-1, 1] (lateral 0 for diff-drive).
    Random,
    /// Turn towards the goal, drive when roughly aligned.
    Goal,
    /// The velocity ORCA gives the robot toward its goal, mapped to its drive (reads the state:
    /// slow on the GPU backend, which downloads it every step).
    Orca,
}

#[derive(Debug, Args)]
pub struct RunArgs {
    /// Config: a shipped name (exp1, exp2, exp3, lroom_mixed, corridor_mixed, stress; with the
    /// SNGNN-v2 reward exp1_sngnn, exp2_sngnn, exp3_sngnn), a TOML path or a SocNavGym 0.1.1
    /// YAML path (`.yaml`/`.yml`).
    #[arg(long, default_value = "exp1")]
    pub config: String,
    /// Number of environments.
    #[arg(long, default_value_t = 1024)]
    pub envs: usize,
    /// Steps of the whole batch.
    #[arg(long, default_value_t = 2000)]
    pub steps: usize,
    /// Seed of the batch (and of the random policy).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Backend.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// Policy.
    #[arg(long, value_enum, default_value_t = PolicyChoice::Random)]
    pub policy: PolicyChoice,
    /// CPU threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Config name or path.
    #[arg(long, default_value = "exp1")]
    pub config: String,
    /// Batch sizes, comma separated.
    #[arg(long, value_delimiter = ',', default_values_t = vec![1usize, 64, 1024, 4096],
          value_parser = at_least_one())]
    pub envs: Vec<usize>,
    /// Seconds of measurement per batch size (after a warm-up), more than 0 and at most a day.
    #[arg(long, default_value_t = 2.0, value_parser = seconds)]
    pub seconds: f64,
    /// Backend.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// CPU threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Deliver padded observations (every type padded to its capacity, walls omitted: 135
    /// floats for exp2) instead of the config's.
    #[arg(long)]
    pub padded: bool,
    /// Also step each batch size as two halves on two host threads, each half's readback and
    /// copy overlapping the other's device work (what `send`/`recv` on two batches does from
    /// Python); on the GPU backend each half's host path is reported too. Batch sizes below 2
    /// have no halves.
    #[arg(long)]
    pub halves: bool,
    /// The optional per-step outputs each step delivers (on the GPU backend: reads back).
    #[arg(long, value_enum, default_value_t = StepOutputsChoice::All)]
    pub step_outputs: StepOutputsChoice,
    /// GPU backend only: take the paths a software adapter takes instead of the device's
    /// defaults, every one (no value) or those named (comma separated), so that a run with and
    /// one without measure what the hardware paths buy (compare the per-stage shares).
    #[arg(long, value_enum, value_delimiter = ',', num_args = 0..)]
    pub lane_paths: Option<Vec<LanePath>>,
    /// GPU backend only, for diagnosis: functions of the stage shaders that return at once
    /// (comma separated, e.g. `obs_walls,obs_put`), so that the stage shares and the device's
    /// time say what each costs on the device. The results are wrong, and the device line says
    /// so; a name no shader of the batch defines is refused.
    #[arg(long, value_delimiter = ',')]
    pub leave_out: Vec<String>,
    /// GPU backend only: bytes of per-step outputs per readback piece (default 4 MiB), each
    /// piece a submit and a map of its own, at most four a step; a value above a step's bytes
    /// (1000000000000) reads every step in one piece, so that a run with and one without say
    /// what the pieces cost (the submits and maps) against what they overlap (the host's copy
    /// with the DMA).
    #[arg(long)]
    pub readback_piece_bytes: Option<u64>,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Config file (or shipped name) to validate.
    pub config: String,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Config name or path.
    #[arg(long, default_value = "exp1")]
    pub config: String,
    /// Seed of the episode.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output file: `.gif` for the episode, `.png` for its first frame.
    #[arg(long)]
    pub out: PathBuf,
    /// Policy driving the robot.
    #[arg(long, value_enum, default_value_t = PolicyChoice::Goal)]
    pub policy: PolicyChoice,
    /// Longest side of the image in pixels (default: the config's `render.resolution`).
    #[arg(long)]
    pub size: Option<u32>,
    /// Most steps to draw (default: the whole episode).
    #[arg(long)]
    pub steps: Option<usize>,
}

#[derive(Debug, Args)]
pub struct SoakArgs {
    /// Configs, comma-separated (names or TOML or SocNavGym YAML paths).
    #[arg(long, default_value = "exp1,exp2,exp3")]
    pub configs: String,
    /// Environment steps per config (the whole run; a resumed run counts what is recorded).
    #[arg(long, default_value_t = 10_000_000)]
    pub steps: u64,
    /// Environments per batch.
    #[arg(long, default_value_t = 1024)]
    pub envs: usize,
    /// Seed of the batches and of the random actions.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Backend.
    #[arg(long, value_enum, default_value_t = BackendChoice::Cpu)]
    pub backend: BackendChoice,
    /// CPU threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Environment steps per config between progress records.
    #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(1..))]
    pub chunk: u64,
    /// Check the state's invariants every this many batch steps (outputs are checked every step).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub check_every: u64,
    /// Progress record (JSON): written after every chunk, resumed from when it exists.
    #[arg(long, default_value = "soak.json")]
    pub record: PathBuf,
}

#[derive(Debug, Args)]
pub struct PlayArgs {
    /// Config name or path.
    #[arg(long, default_value = "exp2")]
    pub config: String,
    /// Seed of the first episode (R plays the next of its sequence).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Record every finished episode into this directory: SocNavGym 0.1.1's `NNNNNNNN.json`
    /// and socnav's `NNNNNNNN.socnav.json` (seed, config, actions).
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Drive with the 7 discrete actions (0.1.1's `DiscreteActions`) instead of continuous ones.
    #[arg(long)]
    pub discrete: bool,
    /// Longest side of the scene in pixels (default: the config's `render.resolution`).
    #[arg(long)]
    pub size: Option<u32>,
    /// Playback speed relative to real time (1/16 to 16; +/- change it while playing).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f32,
    /// Quit after this many episodes have ended (default: play until the window closes).
    #[arg(long, value_parser = at_least_one())]
    pub episodes: Option<usize>,
}

#[derive(Debug, Args)]
pub struct HeatmapArgs {
    /// Config with the SNGNN-v2 reward: a shipped name (exp1_sngnn, exp2_sngnn, exp3_sngnn) or a
    /// TOML or SocNavGym YAML path.
    #[arg(long, default_value = "exp2_sngnn")]
    pub config: String,
    /// Seed of the scene.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output PNG file.
    #[arg(long)]
    pub out: PathBuf,
    /// Grid side: the robot is placed at the centres of N × N cells over the room.
    #[arg(long, default_value_t = 40)]
    pub grid: usize,
    /// The robot's heading at every placement (rad, world frame; default: its heading in the
    /// scene).
    #[arg(long, allow_hyphen_values = true)]
    pub heading: Option<f32>,
    /// Longer side of each panel (px).
    #[arg(long, default_value_t = 480)]
    pub size: u32,
}

/// A count of at least 1 (a batch size, episodes).
fn at_least_one() -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(1..)
}

/// Seconds of measurement: a finite number above 0, at most a day.
fn seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(s) if s > 0.0 && s <= 86_400.0 => Ok(s),
        Ok(s) => Err(format!("{s} is not in (0, 86400] seconds")),
        Err(e) => Err(e.to_string()),
    }
}
