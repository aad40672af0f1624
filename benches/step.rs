//! Criterion benches of the step: exp1, exp2, exp3, observations written and read back, DSRNN
//! reward (and SNGNN-v2's in `step_sngnn` and `step_sngnn_gpu`, when its weights are installed),
//! throughput in env-steps per second. The CPU backend at 1, 64, 1,024 and 4,096 environments
//! (SNGNN-v2: 1, 64, 256); the GPU backend at 4,096, 16,384 and 65,536 (SNGNN-v2: 1,024, 4,096,
//! 16,384) when a hardware GPU adapter exists (`SOCNAV_BENCH_GPU=any` takes a software one too,
//! for correctness runs only).
//!
//! `pool_rows`: the GPU backend's reset-pool rows, generated on the host, per second.
//! `obs_rows`: observation rows into the host's outputs, expanded from the device's rows without
//! their one-hot floats or copied whole, bytes per second; `obs_rows_cold` the same for a padded
//! step's 65,536 rows from memory, not from the caches.
//! `obstacle_build`: RVO2's `processObstacles` of an environment's ORCA obstacles (every reset,
//! every pool row and every regrouping builds one), builds per second.
//!
//! `cargo bench --bench step`; record figures in `benches/RESULTS.md` with the machine, batch size,
//! backend and commit.

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use socnav::backend::BackendChoice;
use socnav::{Actions, BatchEnv, Config, EnvOptions};

fn step(c: &mut Criterion) {
    bench_backend(c, "step", BackendChoice::Cpu, &[1, 64, 1024, 4096]);
}

fn step_gpu(c: &mut Criterion) {
    if gpu_adapter("step_gpu") {
        bench_backend(c, "step_gpu", BackendChoice::Gpu, &[4096, 16384, 65536]);
    }
}

/// Whether the GPU benches run: a hardware adapter exists (or any adapter, with
/// `SOCNAV_BENCH_GPU=any`); says why not otherwise.
#[cfg(feature = "gpu")]
fn gpu_adapter(label: &str) -> bool {
    use socnav::backend::gpu::{AdapterPolicy, GpuDevice};
    let any = std::env::var("SOCNAV_BENCH_GPU").is_ok_and(|v| v == "any");
    let policy = if any {
        AdapterPolicy::Any
    } else {
        AdapterPolicy::Hardware
    };
    match GpuDevice::open(policy) {
        Ok(_) => true,
        Err(e) => {
            eprintln!("{label}: SKIPPED ({e}); SOCNAV_BENCH_GPU=any runs it on a software adapter");
            false
        }
    }
}

#[cfg(not(feature = "gpu"))]
fn gpu_adapter(label: &str) -> bool {
    eprintln!("{label}: SKIPPED (built without the `gpu` feature)");
    false
}

const SNGNN_CONFIGS: [&str; 3] = ["exp1_sngnn", "exp2_sngnn", "exp3_sngnn"];

/// Whether the SNGNN-v2 weights are installed; says why not otherwise.
fn sngnn_weights(label: &str) -> bool {
    let weights = socnav::sngnn::weights_path(None).path;
    if !weights.is_file() {
        eprintln!(
            "{label}: SKIPPED (no SNGNN-v2 weights at {}; `socnav sngnn install`)",
            weights.display()
        );
    }
    weights.is_file()
}

/// The SNGNN-v2 reward on the CPU backend (needs the weights: `socnav sngnn install`).
fn step_sngnn(c: &mut Criterion) {
    if sngnn_weights("step_sngnn") {
        bench_configs(
            c,
            "step_sngnn",
            BackendChoice::Cpu,
            &SNGNN_CONFIGS,
            &[1, 64, 256],
        );
    }
}

/// The SNGNN-v2 reward on the GPU backend (issue 6's target: >= 20,000 env-steps/s for exp2 on
/// one H100).
fn step_sngnn_gpu(c: &mut Criterion) {
    if sngnn_weights("step_sngnn_gpu") && gpu_adapter("step_sngnn_gpu") {
        let sizes = [1024, 4096, 16384];
        bench_configs(
            c,
            "step_sngnn_gpu",
            BackendChoice::Gpu,
            &SNGNN_CONFIGS,
            &sizes,
        );
    }
}

fn bench_backend(c: &mut Criterion, label: &str, backend: BackendChoice, sizes: &[usize]) {
    bench_configs(c, label, backend, &["exp1", "exp2", "exp3"], sizes);
}

fn bench_configs(
    c: &mut Criterion,
    label: &str,
    backend: BackendChoice,
    configs: &[&str],
    sizes: &[usize],
) {
    for &name in configs {
        let config = Config::from_name_or_path(name).expect("shipped config");
        let mut group = c.benchmark_group(format!("{label}/{name}"));
        group
            .measurement_time(Duration::from_secs(3))
            .warm_up_time(Duration::from_secs(1))
            .sample_size(20);
        for &n in sizes {
            // Made on the first call, which criterion makes only for a bench its filter selects
            // (`cargo bench -- pool_rows` builds no batch of the step's benches).
            let mut env: Option<BatchEnv> = None;
            // Forward while turning: episodes end by collisions and timeouts, so resets are included.
            let actions = [0.8f32, 0.0, 0.3].repeat(n);
            group.throughput(Throughput::Elements(n as u64));
            group.bench_function(BenchmarkId::from_parameter(n), |b| {
                let env = env.get_or_insert_with(|| {
                    let mut env = BatchEnv::new(
                        config.clone(),
                        EnvOptions {
                            n_envs: n,
                            seed: 0,
                            backend,
                            ..Default::default()
                        },
                    )
                    .expect("valid batch");
                    env.reset(None).expect("reset");
                    env
                });
                b.iter(|| env.step(Actions::Continuous(&actions)).expect("step"));
            });
        }
        group.finish();
    }
}

/// The GPU backend's reset-pool rows (`reset_pool::write_rows`, the rows two episodes ahead the
/// host makes while the device runs a step): 512 rows of exp2 and exp3, on one thread and on
/// every core, in rows per second. On the sixth H100 run's host a row cost about 68 µs of a core
/// inside the step, against about 12 µs on one core of the 2-vCPU machine: this bench says
/// whether that is the core or the threads. `deferred` rows leave their ORCA obstacles to the
/// device (`GpuDevice::obstacles_after_resets`): what the host saves.
fn pool_rows(c: &mut Criterion) {
    use socnav::backend::reset_pool::{Scratches, row_words, write_rows};
    use socnav::systems::reset::ObstacleBuild;
    const ROWS: usize = 512;
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    for name in ["exp2", "exp3"] {
        let config = Config::from_name_or_path(name).expect("shipped config");
        let env = BatchEnv::new(config, EnvOptions::default()).expect("valid batch");
        let params = env.params();
        let caps = env.state().expect("state").strides;
        let layout = env.outputs().strides.layout;
        // Environments spread over a batch of 65,536, each starting its second episode.
        let envs: Vec<usize> = (0..ROWS).map(|i| i * 128).collect();
        let episodes = vec![1u32; ROWS * 128];
        let mut seeds: Vec<u64> = (0..ROWS as u64 * 128).collect();
        let mut group = c.benchmark_group(format!("pool_rows/{name}"));
        group
            .measurement_time(Duration::from_secs(3))
            .warm_up_time(Duration::from_secs(1))
            .sample_size(20)
            .throughput(Throughput::Elements(ROWS as u64));
        let ways = [
            (ObstacleBuild::Now, "threads"),
            (ObstacleBuild::Deferred, "deferred"),
        ];
        for ((obstacles, way), threads) in ways.into_iter().flat_map(|w| [(w, 1), (w, cores)]) {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            let scratches = Scratches::new(caps, layout, obstacles, Some(&pool));
            let mut rows = vec![0u32; ROWS * row_words(caps, layout, obstacles)];
            group.bench_function(BenchmarkId::new(way, threads), |b| {
                b.iter(|| {
                    // New seeds each time: new scenarios, as the step's rows are.
                    for &e in &envs {
                        seeds[e] = socnav::seeds::next_episode_seed(seeds[e]);
                    }
                    let failed = write_rows(
                        params,
                        &envs,
                        &episodes,
                        &seeds,
                        &mut rows,
                        Some(&pool),
                        &scratches,
                    );
                    assert!(failed.is_empty(), "{name}: scenarios failed");
                });
            });
        }
        group.finish();
    }
}

/// `obs_rows`: the GPU backend's readback copies observation rows into the host's outputs from
/// rows without their entity records' one-hot floats, writing those from the counts
/// (`backend::obs_payload::expand`), where it copied whole rows before (`copy_from_slice`): both
/// over 16,384 rows of exp2 (full and padded, real rows of a stepped batch), on one thread and on
/// every core, in bytes of the host's rows a second. The model counts the copy's time as the
/// same either way. These rows stay in the caches from one iteration to the next.
fn obs_rows(c: &mut Criterion) {
    for padded in [false, true] {
        let label = if padded { "padded" } else { "full" };
        let mut group = c.benchmark_group(format!("obs_rows/exp2_{label}"));
        Exp2Rows::new(padded, 16_384).bench(&mut group, 1);
        group.finish();
    }
}

/// `obs_rows_cold`: [`obs_rows`] for a padded step's 65,536 rows, each iteration on the next of
/// [`COLD_SETS`] sets of rows, so that what it reads and writes comes from memory, as in a step
/// of that size, where the copy reads what the device wrote and writes more rows than the caches
/// keep: how far the host's memory, and not the readback's, sets the copy's pace.
fn obs_rows_cold(c: &mut Criterion) {
    let mut group = c.benchmark_group("obs_rows_cold/exp2_padded_65536");
    Exp2Rows::new(true, 65_536).bench(&mut group, COLD_SETS);
    group.finish();
}

/// Sets of rows `obs_rows_cold` goes round: 8 padded steps of 65,536 rows hold 740 MB, more than
/// a server's last-level cache.
const COLD_SETS: usize = 8;

/// Observation rows of exp2 from a stepped batch, whole and as the device keeps them, made when
/// a benchmark first asks for them (not at all where the filter leaves their group out).
struct Exp2Rows {
    padded: bool,
    rows: usize,
    made: std::cell::OnceCell<RowSet>,
}

/// One set of rows: whole, without their one-hot floats, their counts, and outputs to write.
#[derive(Clone)]
struct RowSet {
    layout: socnav::spec::ObsLayout,
    whole: Vec<u32>,
    payload: Vec<u32>,
    counts: Vec<u32>,
    out: Vec<u32>,
}

impl Exp2Rows {
    /// `rows` rows: the rows of a 256-environment batch after 10 steps, over and over.
    fn new(padded: bool, rows: usize) -> Self {
        Self {
            padded,
            rows,
            made: std::cell::OnceCell::new(),
        }
    }

    fn made(&self) -> &RowSet {
        self.made
            .get_or_init(|| RowSet::new(self.padded, self.rows))
    }

    /// Expanding and copying the rows on one thread and on every core, each iteration on the
    /// next of `sets` copies of the rows and their outputs.
    fn bench(
        &self,
        group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
        sets: usize,
    ) {
        use socnav::backend::obs_payload::expand;
        let cores = std::thread::available_parallelism().map_or(1, usize::from);
        group
            .measurement_time(Duration::from_secs(3))
            .warm_up_time(Duration::from_secs(1))
            .sample_size(20)
            .throughput(Throughput::Bytes(
                4 * (self.rows * row_dim(self.padded)) as u64,
            ));
        for threads in [1, cores] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            self.rotating(group, ("expand", threads), sets, |r| {
                expand(&r.layout, 0, &r.payload, &r.counts, &mut r.out, Some(&pool));
            });
            self.rotating(group, ("copy", threads), sets, |r| {
                let dim = r.layout.dim;
                pool.install(|| {
                    use rayon::prelude::*;
                    r.out
                        .par_chunks_mut(512 * dim)
                        .zip(r.whole.par_chunks(512 * dim))
                        .for_each(|(o, w)| o.copy_from_slice(w));
                });
            });
        }
    }

    /// Benchmark `work` (`id`: its name and threads), each iteration on the next of `sets`
    /// copies of the rows and their outputs.
    fn rotating(
        &self,
        group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
        (name, threads): (&str, usize),
        sets: usize,
        mut work: impl FnMut(&mut RowSet),
    ) {
        group.bench_function(BenchmarkId::new(name, threads), |b| {
            let mut all = vec![self.made().clone(); sets];
            let mut k = 0;
            b.iter(|| {
                k = (k + 1) % sets;
                work(&mut all[k]);
            });
        });
    }
}

/// Floats of an exp2 observation row, padded or not.
fn row_dim(padded: bool) -> usize {
    let mut config = Config::from_name_or_path("exp2").expect("shipped config");
    config.observation.padded = padded;
    let caps = socnav::state::Caps::from_config(&config);
    socnav::spec::ObsLayout::new(&caps, &config.observation).dim
}

impl RowSet {
    fn new(padded: bool, rows: usize) -> Self {
        use socnav::backend::obs_payload::{expand, strip_row};
        let mut config = Config::from_name_or_path("exp2").expect("shipped config");
        config.observation.padded = padded;
        let n = 256;
        let options = EnvOptions {
            n_envs: n,
            ..Default::default()
        };
        let mut env = BatchEnv::new(config, options).expect("valid batch");
        env.reset(None).expect("reset");
        let actions = [0.5f32, 0.0, 0.3].repeat(n);
        for _ in 0..10 {
            env.step(Actions::Continuous(&actions)).expect("step");
        }
        let layout = env.outputs().strides.layout;
        let (dim, width) = (layout.dim, layout.payload_dim());
        let whole: Vec<u32> = (0..rows)
            .flat_map(|e| env.outputs().obs[(e % n) * dim..(e % n + 1) * dim].iter())
            .map(|v| v.to_bits())
            .collect();
        let counts: Vec<u32> = (0..rows)
            .flat_map(|e| {
                env.outputs().obs_count[5 * (e % n)..5 * (e % n + 1)]
                    .iter()
                    .copied()
            })
            .collect();
        let mut payload = vec![0u32; rows * width];
        for (row, p) in whole.chunks_exact(dim).zip(payload.chunks_exact_mut(width)) {
            strip_row(&layout, row, p);
        }
        let mut out = vec![0u32; rows * dim];
        expand(&layout, 0, &payload, &counts, &mut out, None);
        assert!(out == whole, "the expanded rows are the whole rows");
        Self {
            layout,
            whole,
            payload,
            counts,
            out,
        }
    }
}

fn obstacle_build(c: &mut Criterion) {
    use socnav::orca::{ObstacleScratch, ObstacleSet, process_obstacles};
    use socnav::systems::orca_obstacles::for_each_polygon;
    const ENVS: usize = 256;
    let mut group = c.benchmark_group("obstacle_build");
    group
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_secs(1))
        .sample_size(20)
        .throughput(Throughput::Elements(ENVS as u64));
    for name in ["exp2", "exp3", "stress"] {
        let config = Config::from_name_or_path(name).expect("shipped config");
        let options = EnvOptions {
            n_envs: ENVS,
            ..Default::default()
        };
        let mut env = BatchEnv::new(config, options).expect("valid batch");
        env.reset(Some(0)).expect("reset");
        let p = *env.params();
        let mut state = env.state().expect("state").clone();
        // Each environment's polygons as its first episode places them.
        let scenes: Vec<Vec<Vec<[f32; 2]>>> = (0..ENVS)
            .map(|e| {
                let mut polygons = Vec::new();
                for_each_polygon(&p, &state.env_chunk(e), 0, |_, polygon| {
                    polygons.push(polygon.to_vec());
                });
                polygons
            })
            .collect();
        let (mut scratch, mut set) = (ObstacleScratch::new(), ObstacleSet::new());
        group.bench_function(name, |b| {
            b.iter(|| {
                for polygons in &scenes {
                    process_obstacles(polygons, &mut scratch, &mut set).expect("valid polygons");
                }
                set.len()
            });
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    step,
    step_gpu,
    step_sngnn,
    step_sngnn_gpu,
    pool_rows,
    obs_rows,
    obs_rows_cold,
    obstacle_build
);
criterion_main!(benches);
