//! The CPU/GPU parity harness of the stage shaders (docs/spec.md, determinism): a shared device,
//! states from real rollouts, a stage run on both backends from the same state, parameters and
//! actions, and a comparison of every state and output column, bit for bit, that names the first
//! differing element.
//!
//! Needs a GPU adapter (lavapipe will do: `apt-get install mesa-vulkan-drivers`). Without one the
//! tests print why and pass, unless `REQUIRE_GPU=1`, which CI sets.

use socnav::backend::gpu::{AdapterPolicy, AdapterSummary, GpuDevice, GpuStages};
use socnav::backend::reset_pool;
use socnav::outputs::Outputs;
use socnav::pipeline::{Batch, STAGES};
use socnav::rng::RngStream;
use socnav::spec::N_INFO;
use socnav::spec::ObsLayout;
use socnav::state::BatchState;
use socnav::state::columns::Elem;
use socnav::{Actions, AutoresetMode, BatchEnv, Config, EnvOptions, StepParams};

/// The shared device, or `None` (after saying why) when there is none and none is required.
/// `GpuDevice::open` shares one device between the tests and opens a new one once it is lost, so
/// a test that loses it (a pipeline its driver cannot compile) fails alone, not every test after
/// it.
pub fn device() -> Option<GpuDevice> {
    match GpuDevice::open(AdapterPolicy::Any) {
        Ok(d) => Some(d),
        Err(e) => {
            super::skip::skip(Some("REQUIRE_GPU"), &format!("no GPU adapter ({e})"));
            None
        }
    }
}

/// Uniform actions in [-1.5, 1.5] (the stages clip), from a seeded stream; the lateral one 0
/// unless the robot is holonomic (as `BatchEnv` requires).
pub fn random_actions(rng: &mut RngStream, n: usize, holonomic: bool) -> Vec<f32> {
    (0..3 * n)
        .map(|k| {
            let a = 3.0 * rng.next_f32() - 1.5;
            if k % 3 == 1 && !holonomic { 0.0 } else { a }
        })
        .collect()
}

/// A batch of `config` after `steps` random steps on the CPU.
pub fn rolled_out(config: Config, n_envs: usize, steps: usize) -> BatchEnv {
    rolled_out_mode(config, AutoresetMode::NextStep, n_envs, steps)
}

/// A batch of `config` in autoreset mode `mode` after `steps` random steps on the CPU.
pub fn rolled_out_mode(
    config: Config,
    mode: AutoresetMode,
    n_envs: usize,
    steps: usize,
) -> BatchEnv {
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs,
            seed: 11,
            autoreset: mode,
            ..Default::default()
        },
    )
    .expect("batch");
    env.reset(None).expect("reset");
    let holonomic = env.params().holonomic != 0;
    let mut rng = RngStream::new(5, 0);
    for _ in 0..steps {
        env.step(Actions::Continuous(&random_actions(
            &mut rng, n_envs, holonomic,
        )))
        .expect("step");
    }
    env
}

/// Run stage `stage` over every environment of `state` and `outputs` on the CPU; `"reset"` is the
/// GPU's masked-reset pass, whose mask is the first action of each environment (its twin is
/// `CpuBackend::reset`).
pub fn cpu_stage(
    stage: &str,
    p: &StepParams,
    state: &mut BatchState,
    outputs: &mut Outputs,
    actions: &[f32],
) {
    if stage == "reset" {
        let mut b = Batch {
            s: state.chunk(),
            o: outputs.chunk(),
            actions: &[],
            sngnn: None,
            error: None,
        };
        for e in 0..b.n_envs() {
            if actions[3 * e] != 0.0 {
                b.s.pending_reset[e] = 0;
                b.o.has_final[e] = 0;
                b.o.episode_done[e] = 0;
                socnav::systems::reset::reset_and_observe(p, &mut b, e);
            }
        }
        assert!(b.error.is_none(), "reset: {:?}", b.error);
        return;
    }
    let run = STAGES
        .iter()
        .find(|s| s.name == stage)
        .unwrap_or_else(|| panic!("no stage {stage}"))
        .run;
    let n_envs = state.n_envs;
    let mut b = Batch {
        s: state.chunk(),
        o: outputs.chunk(),
        actions,
        sngnn: None,
        error: None,
    };
    for e in 0..n_envs {
        run(p, &mut b, e);
    }
    assert!(b.error.is_none(), "{stage}: {:?}", b.error);
}

/// A change of the state before a run, to reach the cases a stage decides between.
pub type Perturb = fn(&mut BatchState, &mut Outputs, &StepParams, &mut RngStream);

/// Run `stage` `runs` times from the rolled-out state on both backends, comparing the state and
/// the outputs every time. Without `perturb` the runs chain on each side (each from its own last
/// state); with it, the CPU state and outputs are perturbed before each run and uploaded as the
/// GPU's.
/// Returns how often each of the 7 outcome flags of the info row was raised over the runs (on
/// the CPU), for tests that must see every case; `None` when skipped for want of a device.
pub fn check_parity(
    stage: &'static str,
    config: Config,
    n_envs: usize,
    runs: usize,
    perturb: Option<Perturb>,
) -> Option<[usize; 7]> {
    check_parity_mode(
        stage,
        config,
        AutoresetMode::NextStep,
        n_envs,
        runs,
        perturb,
    )
}

/// Pool rows, one per environment in order, each with the half of the pool it belongs in.
pub type HalfRows = Vec<(usize, Vec<u32>)>;

/// Every environment's next-episode pool row for `state`'s episode counters and next seeds,
/// with the half of the pool a reset from that counter reads (`pool_row_of`).
pub fn next_pool_rows(
    gpu: &GpuStages,
    p: &StepParams,
    state: &BatchState,
    layout: ObsLayout,
) -> HalfRows {
    let envs: Vec<usize> = (0..state.n_envs).collect();
    let words = gpu.pool_row_words();
    let mut rows = vec![0u32; envs.len() * words];
    let scratches = reset_pool::Scratches::new(state.strides, layout, gpu.pool_obstacles(), None);
    let seeds: Vec<u64> = envs.iter().map(|&e| state.next_seed(e)).collect();
    let failed = reset_pool::write_rows(
        p,
        &envs,
        &state.episode,
        &seeds,
        &mut rows,
        None,
        &scratches,
    );
    assert!(failed.is_empty(), "scenario generation failed: {failed:?}");
    rows.chunks_exact(words)
        .enumerate()
        .map(|(e, row)| (((state.episode[e] + 1) & 1) as usize, row.to_vec()))
        .collect()
}

/// Fill the GPU's reset pool with every environment's next-episode row for `state`'s episode
/// counters and next seeds, as `GpuBackend` keeps it.
pub fn fill_pool(gpu: &mut GpuStages, p: &StepParams, state: &BatchState, layout: ObsLayout) {
    for (e, (half, row)) in next_pool_rows(gpu, p, state, layout)
        .into_iter()
        .enumerate()
    {
        gpu.write_pool_rows(half, e, &row);
    }
}

/// [`check_parity`] in autoreset mode `mode`.
pub fn check_parity_mode(
    stage: &'static str,
    config: Config,
    mode: AutoresetMode,
    n_envs: usize,
    runs: usize,
    perturb: Option<Perturb>,
) -> Option<[usize; 7]> {
    check_parity_on(device()?, stage, config, mode, n_envs, runs, perturb)
}

/// The shared device with the other observation paths than its defaults
/// (`GpuPaths::stage_observations`, `GpuPaths::records_in_lanes`), the other ways of
/// running the step's resets (`GpuPaths::resets_in_workgroups`), its regroupings
/// (`GpuPaths::regroups_in_workgroups`) and its obstacle rebuilds
/// (`GpuPaths::obstacles_in_workgroups`), the other place a reset's obstacles are built (the
/// host or the device: `GpuPaths::obstacles_after_resets`), and every step's readback in the
/// most pieces (`GpuPaths::readback_piece_bytes` of 1 KiB), submitted at the other time
/// (`GpuPaths::readback_before_host_work`), and the reset pool's staged rows copied last first
/// (`GpuPaths::scatter_last_first`), so that tests cover the paths a test-sized batch on this
/// device would not take.
pub fn device_other_paths() -> Option<GpuDevice> {
    let mut dev = device()?;
    dev.paths.stage_observations = !dev.paths.stage_observations;
    dev.paths.resets_in_workgroups = !dev.paths.resets_in_workgroups;
    dev.paths.regroups_in_workgroups = !dev.paths.regroups_in_workgroups;
    dev.paths.obstacles_in_workgroups = !dev.paths.obstacles_in_workgroups;
    dev.paths.records_in_lanes = !dev.paths.records_in_lanes;
    dev.paths.obstacles_after_resets = !dev.paths.obstacles_after_resets;
    dev.paths.readback_before_host_work = !dev.paths.readback_before_host_work;
    dev.paths.readback_piece_bytes = 1 << 10;
    dev.paths.scatter_last_first = !dev.paths.scatter_last_first;
    Some(dev)
}

/// The shared device twice: as it is, and with the other way of running the step's resets
/// (`GpuPaths::resets_in_workgroups`: one lane each, or a workgroup's lanes) and the other place
/// their obstacles are built (`GpuPaths::obstacles_after_resets`: the host, or the device after
/// the reset); empty without a device.
pub fn devices_both_reset_ways() -> Vec<GpuDevice> {
    let Some(dev) = device() else {
        return Vec::new();
    };
    let mut other = dev.clone();
    other.paths.resets_in_workgroups = !dev.paths.resets_in_workgroups;
    other.paths.obstacles_after_resets = !dev.paths.obstacles_after_resets;
    vec![dev, other]
}

/// [`check_parity_mode`] on device `dev`.
pub fn check_parity_on(
    dev: GpuDevice,
    stage: &'static str,
    config: Config,
    mode: AutoresetMode,
    n_envs: usize,
    runs: usize,
    perturb: Option<Perturb>,
) -> Option<[usize; 7]> {
    let mut raised = [0usize; 7];
    let env = rolled_out_mode(config, mode, n_envs, 40);
    let p = *env.params();
    let mut cpu = env.state().unwrap().clone();
    let mut cpu_out = env.outputs().clone();
    let mut gpu = GpuStages::new(dev, &p, &cpu, &cpu_out, &[stage]).expect("GPU stages");
    let layout = *env.layout();
    fill_pool(&mut gpu, &p, &cpu, layout);
    let mut from_gpu = cpu.clone();
    let mut from_gpu_out = cpu_out.clone();
    let mut rng = RngStream::new(9, 1);
    let stepping = cpu.stepping.iter().filter(|&&s| s != 0).count();
    assert!(
        stepping > n_envs / 2,
        "most environments step ({stepping} of {n_envs})"
    );
    let mode = parity_mode(gpu.adapter());
    let mut lockstep = Lockstep::default();
    for run in 0..runs {
        if let Some(perturb) = perturb {
            perturb(&mut cpu, &mut cpu_out, &p, &mut rng);
        }
        if perturb.is_some() || mode == Parity::Lockstep {
            gpu.upload_state(&cpu);
            gpu.upload_outputs(&cpu_out);
        }
        // The pool holds each environment's next episode, as GpuBackend keeps it.
        fill_pool(&mut gpu, &p, &cpu, layout);
        let mut actions = random_actions(&mut rng, n_envs, p.holonomic != 0);
        if stage == "reset" {
            // The reset pass's mask is the first action: reset about half the environments.
            for e in 0..n_envs {
                if rng.next_f32() < 0.5 {
                    actions[3 * e] = 0.0;
                }
            }
        }
        cpu_stage(stage, &p, &mut cpu, &mut cpu_out, &actions);
        gpu.upload_actions(&actions);
        gpu.run(stage).expect("GPU stage");
        gpu.download_state(&mut from_gpu).expect("readback");
        gpu.download_outputs(&mut from_gpu_out).expect("readback");
        for e in 0..n_envs {
            for (k, count) in raised.iter_mut().enumerate() {
                *count += usize::from(cpu_out.info[e * N_INFO + k] != 0.0);
            }
        }
        let what = format!("{stage} on {}, run {run}", gpu.adapter());
        agree_or_tally(
            &what,
            mode,
            &mut lockstep,
            (&cpu, &from_gpu),
            (&cpu_out, &from_gpu_out),
        );
    }
    if mode == Parity::Lockstep {
        lockstep.check(stage, gpu.adapter());
        return Some(raised);
    }
    println!(
        "{stage}: {runs} runs over {n_envs} environments bit-identical on {}",
        gpu.adapter()
    );
    Some(raised)
}

/// After a run on both backends, the CPU's and the GPU's state and outputs: bit for bit the same
/// where `mode` asks for it (else a panic naming `what`, the columns and their first
/// differences), or added to `lockstep` to be judged at the end.
pub fn agree_or_tally(
    what: &str,
    mode: Parity,
    lockstep: &mut Lockstep,
    (cpu, gpu): (&BatchState, &BatchState),
    (cpu_out, gpu_out): (&Outputs, &Outputs),
) {
    if mode == Parity::Lockstep {
        lockstep.add(cpu.n_envs, (cpu, gpu), Some((cpu_out, gpu_out)));
        return;
    }
    let differ = cpu.differing_columns(gpu);
    let differ_out = cpu_out.differing_columns(gpu_out);
    assert!(
        differ.is_empty() && differ_out.is_empty(),
        "{what}: state columns {differ:?} and output columns {differ_out:?} differ between CPU \
         and GPU; first differences: {}{}",
        first_differences(&cpu.columns(), |f, u| cpu.pack(f, u), |f, u| gpu.pack(f, u)) + "; ",
        first_differences(
            &cpu_out.columns(),
            |f, u| cpu_out.pack(f, u),
            |f, u| gpu_out.pack(f, u)
        ),
    );
}

/// The first differing element of each differing column of two packed tables with `columns`:
/// "name[env][slot]: cpu vs gpu".
pub fn first_differences(
    columns: &[(&'static str, Elem, usize)],
    pack_cpu: impl Fn(&mut Vec<f32>, &mut Vec<u32>),
    pack_gpu: impl Fn(&mut Vec<f32>, &mut Vec<u32>),
) -> String {
    let (mut cf, mut cu, mut gf, mut gu) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    pack_cpu(&mut cf, &mut cu);
    pack_gpu(&mut gf, &mut gu);
    let total_per_env: usize = columns.iter().map(|c| c.2).sum();
    let n_envs = (cf.len() + cu.len()) / total_per_env.max(1);
    let mut out = Vec::new();
    let mut offset = [0usize; 2];
    for &(name, elem, stride) in columns {
        let k = usize::from(elem == Elem::U32);
        let len = n_envs * stride;
        let range = offset[k]..offset[k] + len;
        offset[k] += len;
        let first = match elem {
            Elem::F32 => range
                .clone()
                .find(|&i| cf[i].to_bits() != gf[i].to_bits() && !(cf[i] == 0.0 && gf[i] == 0.0))
                .map(|i| (i, format!("{:e} vs {:e}", cf[i], gf[i]))),
            Elem::U32 => range
                .clone()
                .find(|&i| cu[i] != gu[i])
                .map(|i| (i, format!("{} vs {}", cu[i], gu[i]))),
        };
        if let Some((i, values)) = first {
            let j = i - range.start;
            out.push(format!(
                "{name}[env {}][{}]: {values}",
                j / stride.max(1),
                j % stride.max(1)
            ));
        }
    }
    out.join("; ")
}

/// Uniform in [lo, hi).
pub fn uniform(rng: &mut RngStream, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * rng.next_f32()
}

/// A shipped config by name.
pub fn config(name: &str) -> Config {
    Config::from_name_or_path(name).expect("shipped config")
}

/// Absolute and relative tolerance of a float after one stage or step from identical states, on
/// adapters that round differently from lavapipe: a few float32 ulps of per-operation
/// rounding, amplified by the iterative parts of the step (ORCA's linear programs, the social
/// force sums) by at most two orders of magnitude.
pub const TOLERANCE: (f32, f32) = (1e-5, 1e-4);

/// The largest share of environment-steps allowed to diverge beyond [`TOLERANCE`] (decisions
/// within rounding of their threshold: collisions, goal reached, ORCA constraint choices).
pub const MAX_DIVERGED: f64 = 0.01;

/// How the CPU and GPU backends are compared on an adapter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parity {
    /// Bit for bit (lavapipe, whose rounding the shaders are written against).
    Exact,
    /// One stage or step at a time from identical states, within [`TOLERANCE`]: hardware
    /// drivers may contract `a·b + c` into a fused multiply-add or divide and take square roots
    /// faster and less exactly.
    Lockstep,
}

/// Exact on lavapipe (Vulkan on llvmpipe; llvmpipe under wgpu's GL backend rounds differently),
/// lockstep elsewhere, unless `SOCNAV_PARITY` (`exact` or `tolerance`) says otherwise.
pub fn parity_mode(adapter: &AdapterSummary) -> Parity {
    match std::env::var("SOCNAV_PARITY").as_deref() {
        Ok("exact") => Parity::Exact,
        Ok("tolerance") => Parity::Lockstep,
        _ if adapter.name.contains("llvmpipe") && adapter.backend == "Vulkan" => Parity::Exact,
        _ => Parity::Lockstep,
    }
}

/// What [`diverged_envs`] found.
#[derive(Debug, Default)]
pub struct Divergence {
    /// Per environment: whether it diverged.
    pub envs: Vec<bool>,
    /// Among the environments that did not, the largest float difference relative to its
    /// bound, and its column.
    pub worst: f32,
    pub worst_column: &'static str,
    /// Per column, the environments it diverged in (a column only when it did).
    pub by_column: Vec<(&'static str, usize)>,
}

impl Divergence {
    /// Add this comparison's per-column counts to `counts`, keeping each column once.
    pub fn tally_columns(&self, counts: &mut Vec<(&'static str, usize)>) {
        for &(name, n) in &self.by_column {
            tally_column(counts, name, n);
        }
    }
}

/// Add `n` divergences of column `name` to `counts`, keeping each column once.
pub fn tally_column(counts: &mut Vec<(&'static str, usize)>, name: &'static str, n: usize) {
    match counts.iter_mut().find(|(c, _)| *c == name) {
        Some((_, total)) => *total += n,
        None => counts.push((name, n)),
    }
}

/// The columns of `counts` that diverged most often, most first, as "name (n)", at most `k`.
pub fn most_diverged(counts: &[(&'static str, usize)], k: usize) -> String {
    let mut sorted = counts.to_vec();
    sorted.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    let names: Vec<String> = sorted
        .iter()
        .take(k)
        .map(|(c, n)| format!("{c} ({n})"))
        .collect();
    names.join(", ")
}

/// How far apart two floats may be under `(atol, rtol)`: `atol + rtol·max(|a|, |b|)`.
fn bound(a: f32, b: f32, (atol, rtol): (f32, f32)) -> f32 {
    atol + rtol * a.abs().max(b.abs())
}

/// Whether `a` and `b` are a whole turn (2π) apart within the bound: the same angle, wrapped the
/// other way at ±π.
fn a_turn_apart(a: f32, b: f32, tolerance: (f32, f32)) -> bool {
    ((a - b).abs() - std::f32::consts::TAU).abs() <= bound(a, b, tolerance)
}

/// Whether two floats agree under `tolerance` as [`diverged_envs`] judges them: equal, both NaN,
/// within the bound, or a turn apart.
pub fn floats_agree(a: f32, b: f32, tolerance: (f32, f32)) -> bool {
    a == b
        || (a.is_nan() && b.is_nan())
        || (a - b).abs() <= bound(a, b, tolerance)
        || a_turn_apart(a, b, tolerance)
}

/// A lockstep comparison accumulated over runs (adapters other than lavapipe: [`Parity`]):
/// environment-runs compared, those that diverged beyond [`TOLERANCE`], the columns they
/// diverged in, and among the floats that agreed the one closest to its bound.
#[derive(Debug, Default)]
pub struct Lockstep {
    pub compared: usize,
    pub diverged: usize,
    pub by_column: Vec<(&'static str, usize)>,
    /// The largest float difference relative to its bound in an environment that did not
    /// diverge, and its column ("" while every float was identical).
    pub worst: f32,
    pub worst_column: &'static str,
}

impl Lockstep {
    /// Compare one run's state (and outputs, where given) of `n_envs` environments, CPU against
    /// GPU, and count it; an environment diverged when any of them did.
    pub fn add(
        &mut self,
        n_envs: usize,
        state: (&BatchState, &BatchState),
        outputs: Option<(&Outputs, &Outputs)>,
    ) {
        let mut envs = self.state_verdicts(n_envs, state);
        if let Some((cpu, gpu)) = outputs {
            let in_outputs = self.verdicts(
                n_envs,
                &cpu.columns(),
                |f, u| cpu.pack(f, u),
                |f, u| gpu.pack(f, u),
            );
            for (d, o) in envs.iter_mut().zip(&in_outputs) {
                *d |= *o;
            }
        }
        self.add_envs(&envs);
    }

    /// [`Lockstep::add`] of a step whose outputs the GPU batch delivered in part: its output
    /// columns that `delivered` rejects are not compared (their host copies are stale).
    pub fn add_delivered(
        &mut self,
        n_envs: usize,
        state: (&BatchState, &BatchState),
        (cpu, gpu): (&Outputs, &Outputs),
        delivered: impl Fn(&str) -> bool,
    ) {
        let mut envs = self.state_verdicts(n_envs, state);
        let d = diverged_envs_in(
            &cpu.columns(),
            delivered,
            n_envs,
            |f, u| cpu.pack(f, u),
            |f, u| gpu.pack(f, u),
            TOLERANCE,
        );
        self.tally(&d);
        for (e, o) in envs.iter_mut().zip(&d.envs) {
            *e |= *o;
        }
        self.add_envs(&envs);
    }

    /// Per environment, whether its state diverged (its columns tallied, not yet counted: the
    /// caller adds the verdicts with [`Lockstep::add_envs`], with its own where it has more).
    pub fn state_verdicts(
        &mut self,
        n_envs: usize,
        (cpu, gpu): (&BatchState, &BatchState),
    ) -> Vec<bool> {
        self.verdicts(
            n_envs,
            &cpu.columns(),
            |f, u| cpu.pack(f, u),
            |f, u| gpu.pack(f, u),
        )
    }

    /// [`diverged_envs`] of two packed tables, its columns and its worst agreeing float tallied.
    fn verdicts(
        &mut self,
        n_envs: usize,
        columns: &[(&'static str, Elem, usize)],
        pack_cpu: impl Fn(&mut Vec<f32>, &mut Vec<u32>),
        pack_gpu: impl Fn(&mut Vec<f32>, &mut Vec<u32>),
    ) -> Vec<bool> {
        let d = diverged_envs(columns, n_envs, pack_cpu, pack_gpu, TOLERANCE);
        self.tally(&d);
        d.envs
    }

    /// Tally `d`'s columns and its worst agreeing float.
    fn tally(&mut self, d: &Divergence) {
        d.tally_columns(&mut self.by_column);
        if d.worst > self.worst {
            (self.worst, self.worst_column) = (d.worst, d.worst_column);
        }
    }

    /// Count one run's per-environment verdicts (true: diverged).
    pub fn add_envs(&mut self, diverged: &[bool]) {
        self.compared += diverged.len();
        self.diverged += diverged.iter().filter(|&&d| d).count();
    }

    /// Say what was found for `what` on `adapter`, and fail when more than [`MAX_DIVERGED`] of
    /// the environment-runs diverged.
    pub fn check(&self, what: &str, adapter: &AdapterSummary) {
        let most = match most_diverged(&self.by_column, 5) {
            m if m.is_empty() => "none".to_string(),
            m => m,
        };
        let agreement = if self.worst_column.is_empty() {
            "every other float identical".to_string()
        } else {
            format!(
                "the others within {:.2} of the tolerance (worst in {})",
                self.worst, self.worst_column
            )
        };
        println!(
            "{what}: {} of {} environment-runs beyond the tolerance {TOLERANCE:?} on {adapter} \
             (most in: {most}); {agreement}",
            self.diverged, self.compared
        );
        assert!(
            self.diverged as f64 <= MAX_DIVERGED * self.compared as f64,
            "{what} on {adapter}: {} of {} environment-runs diverged beyond the tolerance \
             {TOLERANCE:?} (more than {:.1} %; most in: {most})",
            self.diverged,
            self.compared,
            100.0 * MAX_DIVERGED
        );
    }
}

/// Per-environment comparison of two packed tables under a tolerance: an environment
/// *diverged* when any of its u32 values differs or a float differs by more than
/// `atol + rtol·max(|a|, |b|)` (NaN equals NaN, infinities must match). Two floats a whole turn
/// apart within that bound agree: an angle wrapped the other way at ±π (a walker heading along
/// −x has `atan2(±0, vx)` = ±π, and the sign of a rounding-sized `vy` picks which).
pub fn diverged_envs(
    columns: &[(&'static str, Elem, usize)],
    n_envs: usize,
    pack_cpu: impl Fn(&mut Vec<f32>, &mut Vec<u32>),
    pack_gpu: impl Fn(&mut Vec<f32>, &mut Vec<u32>),
    tolerance: (f32, f32),
) -> Divergence {
    diverged_envs_in(columns, |_| true, n_envs, pack_cpu, pack_gpu, tolerance)
}

/// [`diverged_envs`] over the columns `compared` accepts alone (the others are skipped: columns a
/// batch does not deliver, whose host copies are stale by design).
pub fn diverged_envs_in(
    columns: &[(&'static str, Elem, usize)],
    compared: impl Fn(&str) -> bool,
    n_envs: usize,
    pack_cpu: impl Fn(&mut Vec<f32>, &mut Vec<u32>),
    pack_gpu: impl Fn(&mut Vec<f32>, &mut Vec<u32>),
    (atol, rtol): (f32, f32),
) -> Divergence {
    let (mut cf, mut cu, mut gf, mut gu) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    pack_cpu(&mut cf, &mut cu);
    pack_gpu(&mut gf, &mut gu);
    let mut diverged = vec![false; n_envs];
    let mut by_column = Vec::new();
    let mut errors: Vec<(usize, f32, &'static str)> = Vec::new();
    let mut offset = [0usize; 2];
    for &(name, elem, stride) in columns {
        let k = usize::from(elem == Elem::U32);
        let start = offset[k];
        offset[k] += n_envs * stride;
        if !compared(name) {
            continue;
        }
        let mut here = vec![false; n_envs];
        for j in 0..n_envs * stride {
            let env = j / stride.max(1);
            let i = start + j;
            match elem {
                Elem::U32 => here[env] |= cu[i] != gu[i],
                Elem::F32 => {
                    let (a, b) = (cf[i], gf[i]);
                    let tolerance = (atol, rtol);
                    if a == b || (a.is_nan() && b.is_nan()) || a_turn_apart(a, b, tolerance) {
                        continue;
                    }
                    let ratio = (a - b).abs() / bound(a, b, tolerance);
                    if ratio.is_nan() || ratio > 1.0 {
                        here[env] = true;
                    } else {
                        errors.push((env, ratio, name));
                    }
                }
            }
        }
        let count = here.iter().filter(|&&d| d).count();
        if count > 0 {
            by_column.push((name, count));
        }
        for (d, h) in diverged.iter_mut().zip(&here) {
            *d |= *h;
        }
    }
    let (worst, worst_column) = errors.iter().filter(|(env, _, _)| !diverged[*env]).fold(
        (0.0f32, ""),
        |(w, c), &(_, r, n)| if r > w { (r, n) } else { (w, c) },
    );
    Divergence {
        envs: diverged,
        worst,
        worst_column,
        by_column,
    }
}

/// A batch on the CPU backend and its twin on the GPU backend, stepped with the same actions and
/// compared after every step as the adapter allows ([`Parity`]). *Exact*: every state column and
/// every output column the GPU batch delivers (`BatchEnv::step_outputs`) bit for bit, the first
/// difference named at once. *Lockstep*: before every step the GPU batch takes the CPU batch's
/// state ([`BatchEnv::copy_state_from`]), and [`Twins::finish`] requires the steps' state and
/// delivered outputs to agree within [`TOLERANCE`] in all but [`MAX_DIVERGED`] of the
/// environment-steps. Taking the state also resets the GPU backend's host bookkeeping (episode
/// counters, next seeds, reset-pool rows) from it, so what only the host computes, the same code
/// on every adapter, is checked by the exact comparison on lavapipe, which CI runs; lockstep
/// checks the device's arithmetic.
pub struct Twins {
    pub cpu: BatchEnv,
    pub gpu: BatchEnv,
    pub mode: Parity,
    steps: usize,
    lockstep: Lockstep,
}

impl Twins {
    /// `cpu` and `gpu`, reset alike, compared in the mode of the GPU batch's adapter (the
    /// process's shared device, [`device`]).
    pub fn new(cpu: BatchEnv, gpu: BatchEnv) -> Self {
        let adapter = device()
            .expect("a GPU batch exists, so an adapter does")
            .adapter;
        Self {
            cpu,
            gpu,
            mode: parity_mode(&adapter),
            steps: 0,
            lockstep: Lockstep::default(),
        }
    }

    /// Step both batches with `actions` (3 floats per environment) and compare them.
    pub fn step(&mut self, actions: &[f32]) {
        if self.mode == Parity::Lockstep {
            self.gpu
                .copy_state_from(&self.cpu)
                .expect("twins of one shape");
        }
        self.cpu
            .step(Actions::Continuous(actions))
            .expect("CPU step");
        self.gpu
            .step(Actions::Continuous(actions))
            .expect("GPU step");
        self.steps += 1;
        self.compare();
    }

    /// Reset the environments of `mask` (a caller's reset under DISABLED) and compare. In
    /// lockstep the GPU batch takes the CPU's reset state before its next step instead.
    pub fn reset_envs(&mut self, mask: &[bool]) {
        self.cpu.reset_envs(mask).expect("CPU masked reset");
        if self.mode == Parity::Exact {
            self.gpu.reset_envs(mask).expect("GPU masked reset");
            self.compare();
        }
    }

    /// Compare the twins as they stand: bit for bit (and fail at once), or tallied in lockstep.
    pub fn compare(&mut self) {
        let (cs, gs) = (self.cpu.state().unwrap(), self.gpu.state().unwrap());
        let (co, go) = (self.cpu.outputs(), self.gpu.outputs());
        let which = self.gpu.step_outputs();
        if self.mode == Parity::Lockstep {
            let n = self.cpu.n_envs();
            self.lockstep
                .add_delivered(n, (cs, gs), (co, go), |c| which.delivers(c));
            return;
        }
        let differ = cs.differing_columns(gs);
        let differ_out: Vec<_> = co
            .differing_columns(go)
            .into_iter()
            .filter(|c| which.delivers(c))
            .collect();
        assert!(
            differ.is_empty() && differ_out.is_empty(),
            "step {}: state columns {differ:?} and output columns {differ_out:?} differ between \
             CPU and GPU on {}; first differences: {}; {}",
            self.steps,
            self.gpu.device(),
            first_differences(&cs.columns(), |f, u| cs.pack(f, u), |f, u| gs.pack(f, u)),
            first_differences(&co.columns(), |f, u| co.pack(f, u), |f, u| go.pack(f, u)),
        );
    }

    /// The lockstep tally so far (empty in the exact mode).
    pub fn lockstep(&self) -> &Lockstep {
        &self.lockstep
    }

    /// Say what the comparison found for `what`, and in lockstep fail when more than
    /// [`MAX_DIVERGED`] of the environment-steps diverged (the exact comparison has failed
    /// already if anything differed).
    pub fn finish(&self, what: &str) {
        match self.mode {
            Parity::Lockstep => {
                let adapter = device().expect("an adapter").adapter;
                self.lockstep.check(what, &adapter);
            }
            Parity::Exact => println!(
                "{what}: {} steps of {} environments bit-identical on {}",
                self.steps,
                self.cpu.n_envs(),
                self.gpu.device()
            ),
        }
    }
}
