//! The GPU backend: the batch state in device storage buffers and the stages of
//! [`crate::pipeline::STAGES`] as WGSL compute shaders (`shaders/<stage>.wgsl`).
//!
//! - [`device`]: finding and opening an adapter under the policy of docs/spec.md, adapters.
//! - `kit`: buffers, their bindings, checks and readback; `pipelines`: bind group layouts and the
//!   device's pipeline cache (`pipelines::PipelineCache`: each pipeline compiled once per device
//!   and source, whatever the batch size or config).
//! - [`GpuStages`]: the state and the outputs each packed into two storage buffers (every f32
//!   column back to back, every u32 column likewise, in declaration order; offsets and strides
//!   reach the shaders at run time in the uniform `batch`, [`crate::backend::wgsl::BatchLayout`]),
//!   the step parameters, the actions and the reset pool, and one compute pipeline per stage
//!   shader. It runs any sequence of passes in one submit, single stages included, which is what
//!   the CPU/GPU parity tests of each stage need (`tests/suite/step/<stage>/gpu.rs`, or
//!   `step/<stage>.rs` for a stage with only that test). [`GpuStages::with_sngnn_graphs`] adds
//!   every environment's packed SNGNN-v2 graph and the frame gaps (bind group 1) and the stage
//!   `sngnn_graph`, which records the frame and builds the graph on the device
//!   (`tests/suite/step/sngnn_graph/gpu.rs`); [`GpuStages::attach_sngnn_net`] adds SNGNN-v2's
//!   network over those graphs as the stage `sngnn_score` ([`GpuNet`], [`sngnn_net`]), which writes
//!   each scored environment's raw score into its `r_discomfort_sngnn` column for the reward stage.
//! - [`GpuBackend`]: the whole step in one submit, with one readback of the outputs, and resets
//!   from a pool of rows the host generates off the step's critical path.

pub mod backend;
pub mod device;
pub(crate) mod kit;
pub(crate) mod pipelines;
pub(crate) mod pool_rows;
pub(crate) mod readback;
pub mod sngnn_net;
pub(crate) mod spirv;
mod timeline;
mod vulkan;

pub use backend::GpuBackend;
pub use device::{
    AdapterPolicy, AdapterSummary, DEFAULT_READBACK_PIECE_BYTES, GpuDevice, PATHS_VAR, SHADERS_VAR,
    list_adapters,
};
pub use sngnn_net::GpuNet;

use std::sync::Arc;

use crate::backend::{obs_payload, schedule, wgsl};
use crate::error::SimError;
use crate::outputs::Outputs;
use crate::params::StepParams;
use crate::pipeline::Shader;
use crate::sngnn::history::TickGaps;
use crate::sngnn::model::Model;
use crate::sngnn::packed::PackedLayout;
use crate::sngnn::pieces::Tables;
use crate::state::BatchState;
use crate::systems::reset::ObstacleBuild;
use kit::{
    CreationScope, bind_buffers, bind_kinds, bytes_of, check_binding, map_and_read,
    map_and_read_after, storage_buffer, uniform_buffer, write_buffer_split,
};
use pipelines::{Binding, Groups};
use readback::{StepReadback, words_to_bytes};
use sngnn_net::StepBuffers;
use timeline::Timeline;

/// What a step's readback fills on the host: the outputs, each environment's episode counter,
/// and the threads that copy large columns (the caller alone when `None`).
pub struct StepRead<'a> {
    /// The host's outputs (same batch size and layout).
    pub out: &'a mut Outputs,
    /// One episode counter per environment.
    pub episode: &'a mut [u32],
    /// Threads for copying the outputs.
    pub pool: Option<&'a rayon::ThreadPool>,
}

/// A packed table on the device: every f32 column in one storage buffer, every u32 column in
/// another, and the host copies they are packed from and read back into.
struct DeviceTable {
    f32s: wgpu::Buffer,
    u32s: wgpu::Buffer,
    packed_f32: Vec<f32>,
    packed_u32: Vec<u32>,
}

/// A batch's state, outputs, parameters and actions on the device, and a pipeline per stage
/// shader.
pub struct GpuStages {
    dev: GpuDevice,
    n_envs: usize,
    /// Workgroups along an observation row of the observation pass's `rows` dispatch
    /// (`OBS_ROWS_TILE` floats each), made where the observation is staged.
    obs_row_tiles: u32,
    /// Entity records of a row, where they are written apart (`GpuDevice::records_in_lanes`),
    /// else 0: the rows of the observation pass's `records` dispatch.
    entity_records: u32,
    /// Whether the step's parameters ask for a whole view, which `records` needs to write
    /// anything (a limited sensor's records are the observing lane's).
    whole_view: bool,
    /// Whether `formation` and `social_events` take an environment a workgroup
    /// (`GpuDevice::regroups_in_workgroups`, where the workgroup memory fits).
    regroups_in_workgroups: bool,
    state: DeviceTable,
    outputs: DeviceTable,
    params: wgpu::Buffer,
    actions: wgpu::Buffer,
    pool: wgpu::Buffer,
    /// New pool rows the host wrote back to back in one queue write, waiting to be copied into
    /// their places at the start of the next submit ([`GpuStages::stage_pool_rows`]); never
    /// larger than the pool unless one write's rows are, so that it fits one storage binding.
    pool_staging: wgpu::Buffer,
    /// Those copies: (offset in `pool_staging`, offset in `pool`, bytes); and the bytes of
    /// `pool_staging` they use.
    pool_copies: Vec<(u64, u64, u64)>,
    pool_staged: u64,
    /// The places of the pool (`half * n_envs + env`) whose staged row still waits for its copy,
    /// a bit each: a place staged again before then waits for the earlier copy
    /// ([`GpuStages::stage_pool_rows`]).
    pool_pending: Vec<u64>,
    /// The host threads that copy the large queue writes (the actions, the pool rows) into
    /// wgpu's staging memory ([`GpuStages::set_host_threads`], [`write_buffer_split`]).
    host_threads: Option<Arc<rayon::ThreadPool>>,
    /// The pass that makes those copies in one dispatch (`wgsl::pool_scatter_shader`), and the
    /// list of runs it reads (the count, then `wgsl::POOL_RUN_WORDS` words a run).
    pool_scatter: PoolScatter,
    /// The stages' working memory (`wgsl::ObstacleScratch`).
    scratch: wgpu::Buffer,
    /// The queues of the rare work (`schedule::has_rare_work`) and of the queued rebuilds
    /// (`schedule::REBUILD_QUEUE`): counters cleared before every submit of stages, then the lists.
    rare: wgpu::Buffer,
    pool_row_words: usize,
    readback: wgpu::Buffer,
    step_readback: wgpu::Buffer,
    /// The uniform batch layout.
    batch: wgpu::Buffer,
    /// What a step hands the host ([`readback`]).
    step_read: StepReadback,
    /// Word offset of the `episode` column in the state's u32 buffer.
    episode_offset: usize,
    /// Group 0 (the prelude's bindings), and group 1 (the SNGNN graphs) when the batch has them.
    bind_groups: Vec<wgpu::BindGroup>,
    /// The member masks of the fused passes (`schedule::fused_passes`), mask `m` at byte
    /// `m * mask_stride`: binding 10 of group 0, at a dynamic offset per dispatch.
    #[expect(dead_code, reason = "kept alive for the bind group that binds it")]
    member_masks: wgpu::Buffer,
    mask_stride: u32,
    /// The passes built, by name (`schedule::pass_of`): their pipelines, or `None` for the network
    /// stage ([`Shader::Network`], recorded by [`GpuNet`]).
    pipelines: Vec<(&'static str, Option<PassPipelines>)>,
    /// How many pipelines building this batch compiled rather than found on its device.
    compiled: usize,
    /// The packed SNGNN graphs (u32 and f32 regions), bind group 1, with their layout; only
    /// when built by [`GpuStages::with_sngnn_graphs`].
    sngnn_graphs: Option<(PackedLayout, wgpu::Buffer, wgpu::Buffer)>,
    /// SNGNN-v2's network over those graphs ([`GpuStages::attach_sngnn_net`]).
    sngnn_net: Option<GpuNet>,
    /// Word offset of the `r_discomfort_sngnn` column in the state's f32 buffer.
    sngnn_score_at: usize,
    /// Each environment's network status, as the last readback after the network stage ran read
    /// it (all 0 after a readback with no network run since the one before).
    sngnn_status: Vec<u32>,
    /// the network stage ran since the last readback of the outputs.
    sngnn_unread: bool,
    /// The delivered steps' timestamps, while they are on ([`GpuStages::set_step_timeline`]).
    timeline: Option<Timeline>,
}

/// Every environment's packed SNGNN graph as read back: the u32 regions, then the f32 regions,
/// one stride of `sngnn::packed::PackedLayout` per environment.
pub type PackedGraphs = (Vec<u32>, Vec<f32>);

/// What [`GpuStages::with_sngnn_graphs`] adds: the packed layout and the selection's gaps.
#[derive(Debug, Clone)]
struct SngnnBinding {
    layout: PackedLayout,
    gaps: TickGaps,
}

impl std::fmt::Debug for GpuStages {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuStages")
            .field("adapter", &self.dev.adapter)
            .field("n_envs", &self.n_envs)
            .finish_non_exhaustive()
    }
}

/// The packed SNGNN graph buffers of `n_envs` environments at `layout`'s strides (u32, f32),
/// or why the adapter cannot bind them.
fn sngnn_buffers(
    dev: &GpuDevice,
    n_envs: usize,
    layout: PackedLayout,
) -> Result<(PackedLayout, wgpu::Buffer, wgpu::Buffer), SimError> {
    // The prelude's 8 storage bindings, the two graph regions and the frame gaps.
    const BINDINGS: u32 = 11;
    if dev.limits.max_storage_buffers_per_shader_stage < BINDINGS {
        return Err(SimError::BackendUnavailable(format!(
            "{} allows {} storage buffers per shader stage; the SNGNN graph pass needs {BINDINGS}",
            dev.adapter.name, dev.limits.max_storage_buffers_per_shader_stage
        )));
    }
    let u_bytes = bytes_of::<u32>(n_envs * layout.u32_stride());
    let f_bytes = bytes_of::<f32>(n_envs * layout.f32_stride());
    check_binding(
        dev,
        &format!("the packed SNGNN graphs of {n_envs} environments"),
        u_bytes.max(f_bytes),
    )?;
    // Buffers are created zeroed, as the graphs of environments that never built one are.
    Ok((
        layout,
        storage_buffer(dev, "sngnn graphs u32", u_bytes),
        storage_buffer(dev, "sngnn graphs f32", f_bytes),
    ))
}

/// Pool rows the staging buffer first has room for ([`GpuStages::stage_pool_rows`]; it grows).
pub const POOL_STAGING_ROWS: usize = 64;

/// How the reset pool's rows hold their ORCA obstacles on a device that rebuilds them after each
/// reset (`after_resets`, `GpuDevice::obstacles_after_resets`) or not.
fn obstacle_build(after_resets: bool) -> ObstacleBuild {
    if after_resets {
        ObstacleBuild::Deferred
    } else {
        ObstacleBuild::Now
    }
}

/// A buffer the host writes rows into and the device copies from, of `words` words.
fn staging_buffer(dev: &GpuDevice, words: usize) -> wgpu::Buffer {
    storage_buffer(dev, "pool staging", bytes_of::<u32>(words))
}

/// The pool scatter pass (`wgsl::pool_scatter_shader`): its pipeline, its bind group layout, and
/// the list of runs it reads, which grows as a step's runs need.
struct PoolScatter {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    runs: wgpu::Buffer,
    /// The list's words on the host, kept between steps.
    list: Vec<u32>,
}

impl PoolScatter {
    /// The pass on `dev` (compiled once per device), with whether this call compiled it.
    fn new(dev: &GpuDevice) -> Result<(Self, bool), SimError> {
        let read = Binding::Storage { read_only: true };
        let group = vec![read, read, Binding::Storage { read_only: false }];
        let (pipeline, layout, compiled) = dev.pipelines.one_group_pipeline(
            dev,
            wgsl::POOL_SCATTER_PASS,
            group,
            &wgsl::pool_scatter_shader(dev.scatter_last_first),
        )?;
        // Room for a staging buffer's first rows in runs of one; it grows past that as needed.
        let runs = storage_buffer(
            dev,
            "pool runs",
            bytes_of::<u32>(1 + POOL_STAGING_ROWS * wgsl::POOL_RUN_WORDS),
        );
        let this = Self {
            pipeline,
            layout,
            runs,
            list: Vec::new(),
        };
        Ok((this, compiled))
    }

    /// Record into `enc` the copies `copies` ((from, to, bytes): from `staged` into `pool`) as
    /// one dispatch, its list of runs written to the device before the submit's work.
    fn record(
        &mut self,
        dev: &GpuDevice,
        enc: &mut wgpu::CommandEncoder,
        (staged, pool): (&wgpu::Buffer, &wgpu::Buffer),
        copies: &[(u64, u64, u64)],
    ) {
        // Word offsets within one storage binding, which WGSL indexes with a u32, as every
        // shader of the batch does.
        let word = |bytes: u64| u32::try_from(bytes / 4).unwrap_or(u32::MAX);
        self.list.clear();
        self.list
            .push(u32::try_from(copies.len()).unwrap_or(u32::MAX));
        for &(from, to, size) in copies {
            self.list.extend([word(from), word(to), word(size)]);
        }
        let bytes = words_to_bytes(self.list.len());
        if bytes > self.runs.size() {
            self.runs = storage_buffer(dev, "pool runs", bytes.next_power_of_two());
        }
        dev.queue
            .write_buffer(&self.runs, 0, bytemuck::cast_slice(&self.list));
        let group = bind_buffers(
            dev,
            "pool scatter",
            &self.layout,
            &[staged, &self.runs, pool],
        );
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(wgsl::POOL_SCATTER_PASS),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        let (x, y) = workgroup_grid(
            copies.len(),
            dev.limits.max_compute_workgroups_per_dimension,
        );
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// The stages' working memory of `n_envs` environments (`wgsl::scratch_words`: ORCA's obstacles,
/// the slot permutations and, staged, the observation of `staged_obs_dim` floats), or why the
/// adapter cannot bind it.
fn scratch_buffer(
    dev: &GpuDevice,
    n_envs: usize,
    state: wgsl::Columns<'_>,
    staged_obs_dim: usize,
) -> Result<wgpu::Buffer, SimError> {
    let bytes = bytes_of::<u32>(wgsl::scratch_words(n_envs, state, staged_obs_dim));
    check_binding(
        dev,
        &format!(
            "the working memory of {n_envs} environments (ORCA's obstacles, the staged observation)"
        ),
        bytes,
    )?;
    Ok(storage_buffer(dev, "scratch", bytes))
}

impl DeviceTable {
    /// Buffers for a table packed into `packed_f32`/`packed_u32`, or why they do not fit.
    fn new(
        dev: &GpuDevice,
        what: &str,
        n_envs: usize,
        packed_f32: Vec<f32>,
        packed_u32: Vec<u32>,
    ) -> Result<Self, SimError> {
        for (kind, bytes) in [
            ("f32", bytes_of::<f32>(packed_f32.len())),
            ("u32", bytes_of::<u32>(packed_u32.len())),
        ] {
            check_binding(
                dev,
                &format!("the {kind} {what} columns of {n_envs} environments"),
                bytes,
            )?;
        }
        Ok(Self {
            f32s: storage_buffer(dev, what, bytes_of::<f32>(packed_f32.len())),
            u32s: storage_buffer(dev, what, bytes_of::<u32>(packed_u32.len())),
            packed_f32,
            packed_u32,
        })
    }

    fn largest(&self) -> usize {
        self.packed_f32.len().max(self.packed_u32.len())
    }
}

impl GpuStages {
    /// Upload `state`, `outputs` and `params` and build the pipelines of `stages` (stages of
    /// [`crate::pipeline::STAGES`], or [`schedule::RESET_PASS`]). The reset pool starts zeroed.
    pub fn new(
        dev: GpuDevice,
        params: &StepParams,
        state: &BatchState,
        outputs: &Outputs,
        stages: &[&'static str],
    ) -> Result<Self, SimError> {
        Self::build(dev, params, state, outputs, stages, None)
    }

    /// [`GpuStages::new`] with the SNGNN graph buffers: every environment's packed graph at
    /// `graphs`' strides (zeroed) and the frame selection's gaps, in bind group 1, which makes
    /// the stages only the SNGNN-v2 reward runs (`sngnn_graph`, `sngnn_score`) available among
    /// `stages`. `graphs` is normally `sngnn::graph::capacity(config)`.
    ///
    /// # Errors
    /// `SimError::Usage` when the state has no SNGNN history or the time step has no frame gaps
    /// ([`TickGaps`]); `SimError::BackendUnavailable` when the adapter allows fewer than 10
    /// storage buffers per shader stage; `SimError::OutOfMemory` when the graphs exceed a binding; anything
    /// [`GpuStages::new`] reports.
    pub fn with_sngnn_graphs(
        dev: GpuDevice,
        params: &StepParams,
        state: &BatchState,
        outputs: &Outputs,
        stages: &[&'static str],
        graphs: PackedLayout,
    ) -> Result<Self, SimError> {
        if state.strides.frames == 0 {
            return Err(SimError::Usage(
                "the SNGNN graph passes need a state with the SNGNN frame history (reward.kind = \"sngnn\")".into(),
            ));
        }
        let gaps = TickGaps::new(params.dt, params.episode_length).ok_or_else(|| {
            SimError::Usage(format!(
                "the SNGNN frame selection has no frame gaps at a time step of {} s",
                params.dt
            ))
        })?;
        let binding = SngnnBinding {
            layout: graphs,
            gaps,
        };
        Self::build(dev, params, state, outputs, stages, Some(binding))
    }

    /// [`GpuStages::build_in_scope`], with the device's errors on the way caught
    /// ([`CreationScope`]).
    fn build(
        dev: GpuDevice,
        params: &StepParams,
        state: &BatchState,
        outputs: &Outputs,
        stages: &[&'static str],
        sngnn: Option<SngnnBinding>,
    ) -> Result<Self, SimError> {
        let scope = CreationScope::push(&dev);
        let built = Self::build_in_scope(dev, params, state, outputs, stages, sngnn);
        scope.finish(
            &format!("a batch of {} environments", state.n_envs),
            built,
            Self::device_bytes,
        )
    }

    #[expect(
        clippy::expect_used,
        reason = "the layout is generated from the very columns it is asked for"
    )]
    fn build_in_scope(
        dev: GpuDevice,
        params: &StepParams,
        state: &BatchState,
        outputs: &Outputs,
        stages: &[&'static str],
        sngnn: Option<SngnnBinding>,
    ) -> Result<Self, SimError> {
        let n_envs = state.n_envs;
        let (mut f, mut u) = (Vec::new(), Vec::new());
        state.pack_in(wgsl::DEVICE_ORDER, &mut f, &mut u);
        let state_table = DeviceTable::new(&dev, "state", n_envs, f, u)?;
        // The device's outputs: the host's, each observation row without its one-hot floats
        // (`obs_payload`).
        let out_columns = obs_payload::device_columns(outputs);
        let obs_layout = outputs.strides.layout;
        let (mut f, mut u) = (Vec::new(), Vec::new());
        obs_payload::pack(outputs, &mut f, &mut u);
        let outputs_table = DeviceTable::new(&dev, "output", n_envs, f, u)?;
        let params_buf = storage_buffer(&dev, "step params", size_of::<StepParams>() as u64);
        dev.queue
            .write_buffer(&params_buf, 0, bytemuck::bytes_of(params));
        let actions = storage_buffer(&dev, "actions", bytes_of::<f32>(3 * n_envs));
        let pool_obstacles = obstacle_build(dev.obstacles_after_resets);
        let pool_row_words = wgsl::pool_row_words(&state.columns(), &out_columns, pool_obstacles);
        // Two rows per environment: its next episode's and the one after it.
        let pool_bytes = bytes_of::<u32>(2 * n_envs * pool_row_words);
        check_binding(
            &dev,
            &format!("the reset pool of {n_envs} environments"),
            pool_bytes,
        )?;
        let pool = storage_buffer(&dev, "reset pool", pool_bytes);
        let obs_staged = dev.stage_observations;
        let entity_records = if dev.records_in_lanes {
            obs_layout.entity_records()
        } else {
            0
        };
        let records_apart = entity_records > 0;
        let staged_obs_dim = if obs_staged {
            obs_layout.payload_dim()
        } else {
            0
        };
        let scratch = scratch_buffer(&dev, n_envs, &state.columns(), staged_obs_dim)?;
        let rare = storage_buffer(
            &dev,
            "rare work queues",
            bytes_of::<u32>(schedule::rare_work_words(n_envs)),
        );
        let layout = wgsl::BatchLayout::new(
            n_envs,
            &state.columns(),
            &out_columns,
            &obs_layout,
            sngnn.as_ref().map(|b| wgsl::SngnnSizes {
                caps: &state.strides,
                graphs: &b.layout,
            }),
        )
        .with_staged_observation(obs_staged)
        .with_records_apart(records_apart)
        .with_pool_obstacles(pool_obstacles);
        let layout_at = |column: &str| {
            layout
                .get(column)
                .expect("the batch layout has every column") as usize
        };
        let episode_offset = layout_at("c_episode");
        let sngnn_score_at = layout_at("c_r_discomfort_sngnn");
        let sngnn_graphs = match &sngnn {
            Some(b) => Some(sngnn_buffers(&dev, n_envs, b.layout)?),
            None => None,
        };
        let graph_words = sngnn.as_ref().map_or(0, |b| {
            n_envs * b.layout.u32_stride().max(b.layout.f32_stride())
        });
        let readback = dev.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: bytes_of::<u32>(
                state_table
                    .largest()
                    .max(outputs_table.largest())
                    .max(graph_words)
                    // A step's second copy of finished rows (`readback`).
                    .max(1 + n_envs * wgsl::finished_row_words(&out_columns)),
            ),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // Group 0, the bindings of the prelude (`backend::wgsl::prelude`): params, sf, su,
        // actions, outf, outu, pool, the batch layout, scratch, the rare work's queues, the fused
        // passes' member masks (a dynamic offset per dispatch). With the SNGNN graphs, group 1: the packed graphs and the frame gaps
        // (`backend::wgsl::sngnn_prelude`), bound only by the shaders that use them, so that
        // every other shader is the same pipeline as without them.
        let batch = uniform_buffer(&dev, "batch layout", &layout.words());
        let (step_read, read_compiled) = StepReadback::new(
            &dev,
            n_envs,
            &state.columns(),
            &out_columns,
            obs_layout,
            readback::Tables {
                f32s: &outputs_table.f32s,
                u32s: &outputs_table.u32s,
                batch: &batch,
            },
        )?;
        // A step's readback: the outputs (the selective copy of `step_read`, or the whole
        // table), the state's episode counters and, with the SNGNN graphs, the network's status
        // words.
        let status_words = if sngnn.is_some() { n_envs } else { 0 };
        let table_words = (outputs_table.packed_f32.len() + outputs_table.packed_u32.len())
            .max(step_read.most_words());
        let step_readback = dev.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("step readback"),
            size: bytes_of::<u32>(table_words + n_envs + status_words),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (member_masks, mask_stride) = member_mask_table(&dev);
        let storage = |read_only| Binding::Storage { read_only };
        let mut bound = vec![vec![
            (&params_buf, storage(true)),
            (&state_table.f32s, storage(false)),
            (&state_table.u32s, storage(false)),
            (&actions, storage(true)),
            (&outputs_table.f32s, storage(false)),
            (&outputs_table.u32s, storage(false)),
            (&pool, storage(true)),
            (&batch, Binding::Uniform),
            (&scratch, storage(false)),
            (&rare, storage(false)),
            (&member_masks, Binding::DynamicUniform),
        ]];
        let gaps = sngnn.as_ref().map(|b| {
            let gaps = storage_buffer(
                &dev,
                "sngnn frame gaps",
                bytes_of::<u32>(b.gaps.words().len()),
            );
            dev.queue
                .write_buffer(&gaps, 0, bytemuck::cast_slice(&b.gaps.words()));
            gaps
        });
        if let (Some((_, gu, gf)), Some(gaps)) = (&sngnn_graphs, &gaps) {
            bound.push(vec![
                (gu, storage(false)),
                (gf, storage(false)),
                (gaps, storage(true)),
            ]);
        }
        let groups: Groups = bound
            .iter()
            .map(|g| g.iter().map(|&(_, kind)| kind).collect())
            .collect();
        let (bind_layouts, _) = dev.pipelines.layout(&dev, &groups);
        let bind_groups = bound
            .iter()
            .zip(&bind_layouts)
            .map(|(g, l)| bind_kinds(&dev, "stage bindings", l, g))
            .collect();
        let columns = state.columns();
        let classes = wgsl::SizeClasses::of(&columns);
        let mut prelude = wgsl::prelude(&columns, &out_columns, &classes);
        if dev.poison_orca_lists {
            prelude = wgsl::with_poisoned_orca_lists(&prelude);
        }
        if dev.resets_in_workgroups {
            prelude = wgsl::with_resets_in_workgroups(&prelude);
        }
        // The regroupings on a workgroup's lanes where the device asks for it and their
        // workgroup memory fits.
        let regroups_in_workgroups = dev.regroups_in_workgroups
            && wgsl::regroup_workgroup_bytes(&classes)
                <= dev.limits.max_compute_workgroup_storage_size as usize;
        if regroups_in_workgroups {
            prelude = wgsl::with_regroups_in_workgroups(&prelude);
        }
        // The obstacle rebuilds in workgroup memory where the device asks for it and the
        // environment's region fits.
        let fits = wgsl::ObstacleScratch::of(&columns).words <= wgsl::OBSTACLES_IN_WORKGROUP_WORDS
            && dev.limits.max_compute_workgroup_storage_size as usize
                >= 4 * wgsl::REBUILD_WORKGROUP_WORDS;
        let rebuild = if dev.obstacles_in_workgroups && fits {
            Rebuild::InWorkgroups
        } else {
            Rebuild::PerLane
        };
        let pool_staging = staging_buffer(&dev, POOL_STAGING_ROWS * pool_row_words);
        let (pool_scatter, scatter_compiled) = PoolScatter::new(&dev)?;
        let mut pipelines: Vec<(&'static str, _)> = Vec::with_capacity(stages.len());
        let mut compiled = usize::from(read_compiled) + usize::from(scatter_compiled);
        let mut left_out = Vec::new();
        for &stage in stages {
            let pass = schedule::pass_of(stage);
            if pipelines.iter().any(|(p, _)| *p == pass) {
                continue;
            }
            let ways = Ways {
                rebuild,
                records_apart,
                obstacles_after_resets: dev.obstacles_after_resets,
            };
            let built = build_pass(&dev, stage, pass, &groups, &prelude, ways, &mut left_out)?;
            compiled += built.as_ref().map_or(0, |b| b.1);
            pipelines.push((pass, built.map(|b| b.0)));
        }
        let unknown: Vec<&str> = dev
            .leave_out
            .iter()
            .filter(|name| !left_out.contains(name))
            .map(String::as_str)
            .collect();
        if !unknown.is_empty() {
            return Err(SimError::Usage(format!(
                "functions to leave out that no shader of the batch defines: {}",
                unknown.join(", ")
            )));
        }
        let this = Self {
            dev,
            n_envs,
            obs_row_tiles: (obs_layout.payload_dim() as u32).div_ceil(wgsl::OBS_ROWS_TILE),
            entity_records: u32::try_from(entity_records).unwrap_or(u32::MAX),
            whole_view: params.obs_partial == 0,
            regroups_in_workgroups,
            state: state_table,
            outputs: outputs_table,
            params: params_buf,
            actions,
            pool,
            pool_staging,
            pool_copies: Vec::new(),
            pool_staged: 0,
            pool_pending: vec![0; (2 * n_envs).div_ceil(64)],
            host_threads: None,
            pool_scatter,
            scratch,
            rare,
            pool_row_words,
            readback,
            step_readback,
            batch,
            step_read,
            episode_offset,
            bind_groups,
            member_masks,
            mask_stride,
            pipelines,
            compiled,
            sngnn_graphs,
            sngnn_net: None,
            sngnn_score_at,
            sngnn_status: vec![0; status_words],
            sngnn_unread: false,
            timeline: None,
        };
        this.write(&this.state);
        this.write(&this.outputs);
        Ok(this)
    }

    /// The adapter the stages run on.
    pub fn adapter(&self) -> &AdapterSummary {
        &self.dev.adapter
    }

    /// The adapter, and the ways taken: whether the pipelines run the backend's own SPIR-V
    /// (`spirv`: the ORCA lists not zeroed), with its storage-buffer bounds checked by the driver
    /// or clamped in the shaders (`spirv::BufferBounds`), or the WGSL as wgpu compiles it; how
    /// the observations are written (`GpuDevice::stage_observations`) and their entity records
    /// (`GpuDevice::records_in_lanes`, where the batch's rows have any), the resets run
    /// (`GpuDevice::resets_in_workgroups`), the obstacles are rebuilt
    /// (`GpuDevice::obstacles_in_workgroups`, where the batch's passes rebuild any) and a reset's
    /// obstacles are built (`GpuDevice::obstacles_after_resets`) and the memory the readback is
    /// mapped from (`GpuDevice::readback_memory`) and the queue writes staged in
    /// (`GpuDevice::staging_memory`).
    pub fn device_description(&self) -> String {
        let bounds = if self.dev.driver_checks_buffers {
            "buffer bounds checked by the driver (robustBufferAccess2)"
        } else {
            "buffer bounds clamped in the shaders"
        };
        let fusing = match self.dev.contraction {
            spirv::Contraction::Forbidden => "no multiply-add fused",
            spirv::Contraction::Allowed => "multiply-adds left to the driver to fuse",
        };
        let shaders = if self.dev.own_spirv {
            format!("socnav's SPIR-V, {fusing}, {bounds}")
        } else {
            "WGSL through wgpu".to_owned()
        };
        let observations = if self.dev.stage_observations {
            "staged through workgroup memory"
        } else {
            "written in place"
        };
        let resets = if self.dev.resets_in_workgroups {
            "a workgroup's lanes each"
        } else {
            "one lane each"
        };
        let regroups = if self.regroups_in_workgroups {
            "a workgroup's lanes each"
        } else {
            "one lane each"
        };
        let in_workgroups = self.pipelines.iter().any(|(_, p)| {
            p.as_ref()
                .is_some_and(|p| matches!(p.rebuild, Some((_, Rebuild::InWorkgroups))))
        });
        let rebuilds = if in_workgroups {
            "in workgroup memory"
        } else {
            "over the scratch buffer"
        };
        let left_out = if self.dev.leave_out.is_empty() {
            String::new()
        } else {
            format!(
                "; DIAGNOSIS, results wrong: functions left out: {}",
                self.dev.leave_out.join(", ")
            )
        };
        let records = if self.entity_records > 0 {
            "a lane each"
        } else {
            "in the observing lane"
        };
        let reset_obstacles = match self.pool_obstacles() {
            ObstacleBuild::Now => "built on the host",
            ObstacleBuild::Deferred => "rebuilt on the device",
        };
        let pieces = match self.step_read.pieces() {
            1 => "one piece".to_owned(),
            n => format!("{n} pieces"),
        };
        let memory = self
            .dev
            .readback_memory()
            .map_or(String::new(), |m| format!(", mapped from {m}"));
        let staging = self
            .dev
            .staging_memory()
            .map_or(String::new(), |m| format!("; queue writes staged in {m}"));
        let submitted = if self.dev.readback_before_host_work {
            "before"
        } else {
            "after"
        };
        format!(
            "{}; shaders: {shaders}; observations {observations}; entity records {records}; \
             resets on {resets}; regroupings on {regroups}; obstacle rebuilds {rebuilds}; \
             a reset's obstacles {reset_obstacles}; per-step outputs read back in \
             {pieces}{memory}, submitted {submitted} the host's work{staging}{left_out}",
            self.dev.adapter
        )
    }

    /// Bytes of the buffers the batch holds on its device (its network's excepted).
    pub fn device_bytes(&self) -> u64 {
        let graphs = self
            .sngnn_graphs
            .as_ref()
            .map_or(0, |(_, u, f)| u.size() + f.size());
        [
            &self.state.f32s,
            &self.state.u32s,
            &self.outputs.f32s,
            &self.outputs.u32s,
            &self.params,
            &self.actions,
            &self.pool,
            &self.pool_staging,
            &self.pool_scatter.runs,
            &self.scratch,
            &self.rare,
            &self.readback,
            &self.step_readback,
            &self.batch,
        ]
        .iter()
        .map(|b| b.size())
        .sum::<u64>()
            + graphs
            + self.step_read.device_bytes()
    }

    /// Whether the device was lost, as `SimError::Device` (see [`GpuDevice::lost`]).
    pub fn check_lost(&self) -> Result<(), SimError> {
        self.dev.check_lost()
    }

    /// Add SNGNN-v2's network (`model` with `tables`) over the packed graphs, as the stage
    /// `sngnn_score`: each environment with a graph gets the room node's first output written
    /// into its `r_discomfort_sngnn` state column, where the reward stage clamps it (the
    /// `sngnn_graph` pass empties the graphs of the environments the reward does not score).
    ///
    /// # Errors
    /// `SimError::Usage` without the graph buffers ([`GpuStages::with_sngnn_graphs`]);
    /// `SimError::OutOfMemory` when the network does not fit the adapter.
    pub fn attach_sngnn_net(&mut self, model: &Model, tables: &Tables) -> Result<(), SimError> {
        let Some((layout, gu, gf)) = &self.sngnn_graphs else {
            return Err(SimError::Usage(
                "SNGNN-v2's network needs the SNGNN graph buffers (GpuStages::with_sngnn_graphs)"
                    .into(),
            ));
        };
        let score_at = self.sngnn_score_at;
        self.sngnn_net = Some(GpuNet::in_step(
            self.dev.clone(),
            model,
            tables,
            *layout,
            self.n_envs,
            StepBuffers {
                buffers: [gu.clone(), gf.clone()],
                scores: self.state.f32s.clone(),
                score_at,
            },
        )?);
        Ok(())
    }

    /// How many pipelines building this batch compiled (its stages' and, once attached, its
    /// network's), rather than found compiled on its device: 0 for a second batch of a config on
    /// the same device, whatever its size.
    pub fn pipelines_compiled(&self) -> usize {
        self.compiled
            + self
                .sngnn_net
                .as_ref()
                .map_or(0, GpuNet::pipelines_compiled)
    }

    /// The error of the last step's SNGNN-v2 network, if an environment's graph could not be
    /// scored (an edge outside the tables, a graph beyond its layout).
    pub fn sngnn_failure(&self) -> Option<SimError> {
        sngnn_net::failure(&self.sngnn_status)
    }

    fn write(&self, t: &DeviceTable) {
        let q = &self.dev.queue;
        q.write_buffer(&t.f32s, 0, bytemuck::cast_slice(&t.packed_f32));
        q.write_buffer(&t.u32s, 0, bytemuck::cast_slice(&t.packed_u32));
    }

    /// Replace the device's state with `state` (same batch size and capacities).
    pub fn upload_state(&mut self, state: &BatchState) {
        let t = &mut self.state;
        t.packed_f32.clear();
        t.packed_u32.clear();
        state.pack_in(wgsl::DEVICE_ORDER, &mut t.packed_f32, &mut t.packed_u32);
        self.write(&self.state);
    }

    /// Replace the device's outputs with `outputs` (same batch size and layout).
    pub fn upload_outputs(&mut self, outputs: &Outputs) {
        let t = &mut self.outputs;
        t.packed_f32.clear();
        t.packed_u32.clear();
        obs_payload::pack(outputs, &mut t.packed_f32, &mut t.packed_u32);
        self.write(&self.outputs);
    }

    /// The host threads that copy large queue writes (the actions, the pool rows) into wgpu's
    /// staging memory, which on a discrete GPU one core fills at a fraction of the bus's speed
    /// (`kit::write_buffer_split`); without them, the caller's thread copies.
    pub fn set_host_threads(&mut self, pool: Option<Arc<rayon::ThreadPool>>) {
        self.host_threads = pool;
    }

    /// Set the actions of the next stages: 3 floats per environment.
    pub fn upload_actions(&mut self, actions: &[f32]) {
        assert_eq!(actions.len(), 3 * self.n_envs, "3 actions per environment");
        write_buffer_split(
            &self.dev,
            &self.actions,
            0,
            bytemuck::cast_slice(actions),
            self.host_threads.as_deref(),
        );
    }

    /// Replace the step constants.
    pub fn upload_params(&mut self, params: &StepParams) {
        self.whole_view = params.obs_partial == 0;
        self.dev
            .queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(params));
    }

    /// Words of one reset-pool row ([`wgsl::pool_row_words`]).
    pub fn pool_row_words(&self) -> usize {
        self.pool_row_words
    }

    /// How the rows written into the reset pool must hold their ORCA obstacles: left to the
    /// device, which rebuilds them after each reset, where the device asks for it
    /// (`GpuDevice::obstacles_after_resets`), else built
    /// (`crate::backend::reset_pool::RowScratch::new`).
    pub fn pool_obstacles(&self) -> ObstacleBuild {
        obstacle_build(self.dev.obstacles_after_resets)
    }

    /// Write `rows` (whole pool rows) into the reset pool from environment `first_env` on, in the
    /// half of the pool for episode counters of parity `half` (0 or 1): the rows that start
    /// episodes after counters of the other parity, since a reset moves the counter on
    /// (`pool_row_of` in `shaders/common/pool_reset.wgsl`). A place whose row
    /// [`GpuStages::stage_pool_rows`] staged and the next submit has not copied yet takes that
    /// row after this one (queue writes land before a submit's work).
    pub fn write_pool_rows(&mut self, half: usize, first_env: usize, rows: &[u32]) {
        assert!(half < 2, "the pool has two halves");
        assert_eq!(
            rows.len() % self.pool_row_words.max(1),
            0,
            "whole pool rows"
        );
        let offset = self.pool_row_at(half, first_env);
        self.dev
            .queue
            .write_buffer(&self.pool, offset, bytemuck::cast_slice(rows));
    }

    /// Write `rows` (whole pool rows, back to back) to the device in one queue write, to be
    /// copied into the pool before the next submitted work: `runs` lists, in order, each run of
    /// consecutive environments of one half (as [`GpuStages::write_pool_rows`] takes them) and
    /// its number of rows. A queue write per run costs several microseconds of the host's time
    /// each, and the rows of a step are scattered; one write, and one dispatch that moves every
    /// run into place (`wgsl::pool_scatter_shader`), cost less (a copy command per run cost about
    /// 0.7 µs each). A run is copied in pieces of at most `wgsl::POOL_SCATTER_PIECE_WORDS`, a
    /// workgroup each.
    ///
    /// The dispatch's workgroups copy in no particular order, so a place staged again while its
    /// earlier row still waits (a state loaded, new seeds or constants make the host generate a
    /// place's row anew) would race with it: the copies still waiting are then made first, in a
    /// submit of their own, as they are before the staging buffer grows.
    pub fn stage_pool_rows(&mut self, rows: &[u32], runs: &[(usize, usize, usize)]) {
        let bytes = words_to_bytes(rows.len());
        let grows = self.pool_staged + bytes > self.pool_staging.size();
        let restaged = runs
            .iter()
            .any(|&(half, env, n)| self.places(half, env, n).any(|at| self.pending(at)));
        if (grows || restaged) && !self.pool_copies.is_empty() {
            let mut enc = self
                .dev
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("pool rows"),
                });
            self.flush_pool_copies(&mut enc);
            self.dev.queue.submit([enc.finish()]);
        }
        if grows {
            // No larger than the pool (which fits one storage binding) unless the rows are:
            // the pool scatter pass binds the staging buffer whole.
            let words = (2 * self.pool_staging.size() / 4)
                .min(self.pool.size() / 4)
                .max(rows.len() as u64) as usize;
            self.pool_staging = staging_buffer(&self.dev, words);
        }
        write_buffer_split(
            &self.dev,
            &self.pool_staging,
            self.pool_staged,
            bytemuck::cast_slice(rows),
            self.host_threads.as_deref(),
        );
        let piece = words_to_bytes(wgsl::POOL_SCATTER_PIECE_WORDS);
        let mut from = self.pool_staged;
        for &(half, env, n) in runs {
            let to = self.pool_row_at(half, env);
            let size = words_to_bytes(n * self.pool_row_words);
            for at in (0..size).step_by(piece as usize) {
                self.pool_copies
                    .push((from + at, to + at, piece.min(size - at)));
            }
            for at in self.places(half, env, n) {
                self.pool_pending[at / 64] |= 1 << (at % 64);
            }
            from += size;
        }
        self.pool_staged += bytes;
    }

    /// The place of environment `env`'s row in half `half` of the pool: its index among the
    /// pool's rows.
    fn place(&self, half: usize, env: usize) -> usize {
        half * self.n_envs + env
    }

    /// The places of `n` rows from environment `env` on in half `half`.
    fn places(&self, half: usize, env: usize, n: usize) -> std::ops::Range<usize> {
        let first = self.place(half, env);
        first..first + n
    }

    /// Whether place `at` holds a staged row that waits for its copy.
    fn pending(&self, at: usize) -> bool {
        self.pool_pending[at / 64] & (1 << (at % 64)) != 0
    }

    /// Byte offset in the pool of environment `env`'s row in half `half`.
    fn pool_row_at(&self, half: usize, env: usize) -> u64 {
        words_to_bytes(self.place(half, env) * self.pool_row_words)
    }

    /// Record the staged pool rows' copies into `enc` (before its passes): one dispatch of the
    /// pool scatter pass.
    fn flush_pool_copies(&mut self, enc: &mut wgpu::CommandEncoder) {
        if !self.pool_copies.is_empty() {
            let buffers = (&self.pool_staging, &self.pool);
            self.pool_scatter
                .record(&self.dev, enc, buffers, &self.pool_copies);
            self.pool_copies.clear();
            self.pool_pending.fill(0);
        }
        self.pool_staged = 0;
    }

    /// Run stage `stage` over every environment (one dispatch, one submit).
    pub fn run(&mut self, stage: &str) -> Result<(), SimError> {
        self.run_stages(&[stage], None, |_| {})
    }

    /// Run `stages` in order over every environment, one dispatch each, in one submit; with
    /// `read`, the same submit then copies what the step hands the host
    /// (`backend::gpu::readback`: the per-step output columns and the rows of the environments
    /// that finished, or the whole output table after device work that was not read back) and
    /// the episode counters into the step readback buffer, which is read into `read`'s outputs
    /// and counters. The host runs `while_device_works` between the submit and the wait for the
    /// readback; it may stage pool rows ([`GpuStages::stage_pool_rows`]), which reach the pool at
    /// the start of the next submit. Where `stages` regroup or reset, the obstacles of the
    /// environments they queued for it are rebuilt once after them (`record_queued_rebuild`),
    /// with a read in a submit of its own after the readback's.
    pub fn run_stages(
        &mut self,
        stages: &[&str],
        read: Option<StepRead<'_>>,
        while_device_works: impl FnOnce(&mut Self),
    ) -> Result<(), SimError> {
        let started = std::time::Instant::now();
        // The queued rebuilds' one dispatch: at the end of the submit, or where the step is read
        // back, in a submit of its own after the readback's (the host waits for those alone, and
        // copies while the device rebuilds), made before any wait so that no error on the way
        // leaves a queued environment dirty. A driver that holds a submit until the one before it
        // has finished (lavapipe) holds the host there until the readback is done; the H200's did
        // not hold the pieces' submits.
        let queueing = self.last_queueing(stages);
        let mut enc = self
            .dev
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("step"),
            });
        // The step timeline times a step read back whose passes run here (not the read after
        // passes timed alone, `time_passes`).
        let timed = read.is_some() && !stages.is_empty();
        if let Some(t) = self.timeline.as_ref().filter(|_| timed) {
            t.at_start(&mut enc);
        }
        self.begin_submit(&mut enc);
        let selective = read.is_some() && !self.step_read.whole_table_next;
        if selective {
            self.step_read.clear(&mut enc);
        }
        {
            let timeline = self.timeline.as_ref().filter(|_| timed);
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("step"),
                timestamp_writes: timeline.map(Timeline::pass_writes),
            });
            self.bind(&mut pass);
            for dispatch in plan(stages) {
                self.sngnn_unread |= self.record(&mut pass, &dispatch)?;
            }
            if let (None, Some(of)) = (&read, queueing) {
                self.record_queued_rebuild(&mut pass, of)?;
            }
            if selective {
                self.step_read.record(&mut pass);
            }
        }
        let Some(read) = read else {
            self.dev.queue.submit([enc.finish()]);
            while_device_works(self);
            self.step_read.whole_table_next = true;
            return self.dev.take_errors();
        };
        let f_words = self.outputs.packed_f32.len();
        let table_bytes = if selective {
            self.step_read.copy_rows(&mut enc, &self.step_readback)
        } else {
            let (f_bytes, u_bytes) = (
                words_to_bytes(f_words),
                words_to_bytes(self.outputs.packed_u32.len()),
            );
            let rb = &self.step_readback;
            enc.copy_buffer_to_buffer(&self.outputs.f32s, 0, rb, 0, f_bytes);
            enc.copy_buffer_to_buffer(&self.outputs.u32s, 0, rb, f_bytes, u_bytes);
            f_bytes + u_bytes
        };
        let e_bytes = words_to_bytes(self.n_envs);
        let episode_at = words_to_bytes(self.episode_offset);
        let rb = &self.step_readback;
        enc.copy_buffer_to_buffer(&self.state.u32s, episode_at, rb, table_bytes, e_bytes);
        let mut total = table_bytes + e_bytes;
        // Stage timing runs the passes without a read (`time_passes`, or a submit per pass) and
        // reads back after them: the network's status is read if it ran since the last read.
        let scored = std::mem::take(&mut self.sngnn_unread);
        if let (true, Some(net)) = (scored, &self.sngnn_net) {
            enc.copy_buffer_to_buffer(net.status_buffer(), 0, rb, total, e_bytes);
            total += e_bytes;
        }
        let timeline = self.timeline.as_ref().filter(|_| timed);
        let mut piece_bytes = 0;
        if selective {
            let tables = self.output_tables();
            piece_bytes = self.step_read.copy_first_piece(&mut enc, &tables, timeline);
        } else if let Some(t) = timeline {
            t.after_copy(&mut enc, 0);
            t.resolve(&mut enc);
        }
        let mut submits = vec![self.dev.queue.submit([enc.finish()])];
        // The readback's other pieces and the queued rebuild, each in a submit of its own: right
        // after the step's where the driver takes submits as they come; after the host's work
        // that overlaps the step's passes where it may hold a submit until the one before it
        // has finished (`GpuDevice::readback_before_host_work`).
        let early = self.dev.readback_before_host_work;
        if early {
            piece_bytes += self.submit_after_step(selective, timed, queueing, &mut submits)?;
        }
        let working = std::time::Instant::now();
        while_device_works(self);
        let host_work_s = working.elapsed().as_secs_f64();
        if !early {
            piece_bytes += self.submit_after_step(selective, timed, queueing, &mut submits)?;
        }
        let submit_s = started.elapsed().as_secs_f64() - host_work_s;
        let copies = submits.len();
        let mut bytes = total + piece_bytes;
        let rb = &self.step_readback;
        let (status, step_read) = (&mut self.sngnn_status, &self.step_read);
        let StepRead { out, episode, pool } = read;
        let table_words = (table_bytes / 4) as usize;
        let mut copy_s = 0.0;
        let mut finished = Ok(0);
        map_and_read_after(&self.dev, rb, total, Some(submits[0].clone()), |words| {
            let copying = std::time::Instant::now();
            let (table, rest) = words.split_at(table_words);
            let (ep, st) = rest.split_at(episode.len());
            if selective {
                finished = step_read.read_rows(table, out);
            } else {
                let (f, u) = table.split_at(f_words);
                obs_payload::unpack(out, bytemuck::cast_slice(f), u);
            }
            episode.copy_from_slice(ep);
            if scored {
                status.copy_from_slice(st);
            } else {
                status.fill(0);
            }
            copy_s += copying.elapsed().as_secs_f64();
        })?;
        if selective {
            copy_s += step_read.read_pieces(&self.dev, submits, out, pool)?;
        }
        let mut second = false;
        if selective {
            let count = finished?;
            let held = self.step_read.rows_hint();
            if count > held {
                let copying = std::time::Instant::now();
                let (src, at) = self.step_read.rest_at(held);
                let rows =
                    self.read_words_at(src, at, (count - held) * self.step_read.row_words())?;
                self.step_read.scatter(&rows, out)?;
                copy_s += copying.elapsed().as_secs_f64();
                bytes += words_to_bytes(rows.len());
                second = true;
            }
            self.step_read.note_finished(count);
            self.step_read.stats.finished_rows += count as u64;
        } else {
            self.step_read.whole_table_next = false;
            self.step_read.stats.full_reads += 1;
        }
        // The timeline's own readback is not the step's: its time stays out of the wait.
        let timing = std::time::Instant::now();
        if let Some(t) = self.timeline.as_ref().filter(|_| timed) {
            t.read(&self.dev, copies, &mut self.step_read.stats)?;
        }
        let timeline_s = timing.elapsed().as_secs_f64();
        let stats = &mut self.step_read.stats;
        stats.reads += 1;
        stats.bytes += bytes;
        stats.second_reads += u64::from(second);
        stats.copy_s += copy_s;
        stats.submit_s += submit_s;
        stats.wait_s += started.elapsed().as_secs_f64() - copy_s - host_work_s - timeline_s;
        Ok(())
    }

    /// Read back only the optional per-step columns `which` selects from the next step on
    /// ([`crate::outputs::StepOutputs`]).
    pub fn set_step_outputs(&mut self, which: crate::outputs::StepOutputs) {
        self.step_read.select(&self.dev, which);
    }

    /// The host path's totals so far (the pool refill's time is the backend's to add).
    pub fn host_path(&self) -> crate::backend::HostPath {
        self.step_read.stats
    }

    /// Time the passes and readback copies of the following delivered steps on the device's
    /// clock (`HostPath::device_s`, `HostPath::readback_s`), where the device has timestamp
    /// queries; a step records none while this is off.
    pub fn set_step_timeline(&mut self, on: bool) {
        if !on {
            self.timeline = None;
        } else if self.timeline.is_none() {
            self.timeline = Timeline::new(&self.dev, readback::MOST_PIECES);
        }
    }

    /// Record `dispatch` into `pass` (whose bind groups are the batch's): its pass's dispatches,
    /// or the network's. Returns whether the network ran.
    fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        dispatch: &Dispatch<'_>,
    ) -> Result<bool, SimError> {
        let stage = dispatch.first;
        let Some((_, pipeline)) = self.pipelines.iter().find(|(p, _)| *p == dispatch.pass) else {
            return Err(SimError::Usage(format!(
                "stage {stage:?} was not built for this batch"
            )));
        };
        let Some(pipeline) = pipeline else {
            let Some(net) = &self.sngnn_net else {
                return Err(SimError::Usage(format!(
                    "stage {stage:?} needs SNGNN-v2's network (GpuStages::attach_sngnn_net)"
                )));
            };
            net.record(pass);
            self.bind(pass);
            return Ok(true);
        };
        let workgroups = (self.n_envs as u32).div_ceil(wgsl::WORKGROUP_SIZE);
        if let Some(queue) = &pipeline.queue {
            pass.set_pipeline(queue);
            pass.dispatch_workgroups(workgroups, 1, 1);
        }
        pass.set_pipeline(&pipeline.main);
        if let Some(members) = dispatch.members {
            pass.set_bind_group(0, &self.bind_groups[0], &[members * self.mask_stride]);
        }
        pass.dispatch_workgroups(workgroups, 1, 1);
        // A queueing pass's rebuild waits for the submit's end (`record_queued_rebuild`).
        if let Some(rebuild) = &pipeline.rebuild
            && !schedule::queues_rebuilds(dispatch.pass)
        {
            self.dispatch_rebuild(pass, rebuild);
        }
        if let Some(records) = &pipeline.records
            && self.whole_view
            && dispatch.runs(wgsl::OBS_ROWS_STAGE)
        {
            pass.set_pipeline(records);
            pass.dispatch_workgroups(workgroups, self.entity_records, 1);
        }
        if let Some(rows) = &pipeline.rows
            && dispatch.runs(wgsl::OBS_ROWS_STAGE)
        {
            pass.set_pipeline(rows);
            pass.dispatch_workgroups(workgroups, self.obs_row_tiles, 1);
        }
        Ok(false)
    }

    /// Record a rebuild entry point's dispatch into `pass`.
    fn dispatch_rebuild(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        (pipeline, how): &(wgpu::ComputePipeline, Rebuild),
    ) {
        pass.set_pipeline(pipeline);
        match how {
            Rebuild::PerLane => {
                pass.dispatch_workgroups((self.n_envs as u32).div_ceil(wgsl::WORKGROUP_SIZE), 1, 1);
            }
            Rebuild::InWorkgroups => {
                // A workgroup per environment of the batch, at most the device's
                // `rebuild_workgroups` (each then takes every so-many-th queued environment), in
                // rows of at most the device's workgroups per dimension.
                let per_dimension = self.dev.limits.max_compute_workgroups_per_dimension;
                let most =
                    usize::try_from(self.dev.rebuild_workgroups.max(1)).unwrap_or(usize::MAX);
                let (x, y) = workgroup_grid(self.n_envs.min(most), per_dimension);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
    }

    /// The last of `stages` whose rebuilds wait in the queue (`schedule::queues_rebuilds`, with
    /// a rebuild pipeline on this batch: `begin_step` and `autoreset` only where the pool's rows
    /// leave their obstacles to the device), whose pipeline then rebuilds the queue.
    fn last_queueing<'a>(&self, stages: &[&'a str]) -> Option<&'a str> {
        stages.iter().rev().copied().find(|stage| {
            schedule::queues_rebuilds(stage)
                && self.pipelines.iter().any(|(pass, pipelines)| {
                    pass == stage && pipelines.as_ref().is_some_and(|p| p.rebuild.is_some())
                })
        })
    }

    /// Record into `pass` the one rebuild of the ORCA obstacles of every environment that the
    /// submit's regroupings and resets queued (`schedule::REBUILD_QUEUE`), with queueing pass `of`'s
    /// rebuild pipeline (the same entry point in each). It follows the submit's last stage:
    /// nothing in a step reads the obstacles of an environment after it regrouped or reset
    /// (`schedule::queues_rebuilds`), so the rebuild costs the step's latency nothing where it
    /// follows the readback ([`Self::run_stages`]).
    fn record_queued_rebuild(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        of: &str,
    ) -> Result<(), SimError> {
        let rebuild = self
            .pipelines
            .iter()
            .find(|(p, _)| *p == of)
            .and_then(|(_, pipelines)| pipelines.as_ref())
            .and_then(|p| p.rebuild.as_ref())
            .ok_or_else(|| SimError::Internal(format!("pass {of} has no rebuild pipeline")))?;
        self.dispatch_rebuild(pass, rebuild);
        Ok(())
    }

    /// What a step read back submits after its own submit: the readback's other pieces where
    /// the read is `selective` (appended to `submits`, with a timestamp each where `timed`),
    /// then the rebuilds the stages queued, where one of them (`queueing`) did. The bytes the
    /// pieces copy.
    fn submit_after_step(
        &self,
        selective: bool,
        timed: bool,
        queueing: Option<&str>,
        submits: &mut Vec<wgpu::SubmissionIndex>,
    ) -> Result<u64, SimError> {
        let mut bytes = 0;
        if selective {
            let tables = self.output_tables();
            let timeline = self.timeline.as_ref().filter(|_| timed);
            let (others, copied) = self
                .step_read
                .submit_other_pieces(&self.dev, &tables, timeline);
            submits.extend(others);
            bytes = copied;
        }
        if let Some(of) = queueing {
            self.submit_queued_rebuild(of)?;
        }
        Ok(bytes)
    }

    /// The queued rebuilds' dispatch (`record_queued_rebuild`) in a submit of its own, after the
    /// submits made so far.
    fn submit_queued_rebuild(&self, of: &str) -> Result<(), SimError> {
        let mut enc = self
            .dev
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("queued obstacle rebuilds"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("queued obstacle rebuilds"),
                timestamp_writes: None,
            });
            self.bind(&mut pass);
            self.record_queued_rebuild(&mut pass, of)?;
        }
        self.dev.queue.submit([enc.finish()]);
        Ok(())
    }

    /// The output tables and the batch's layout, as the readback copies from them.
    fn output_tables(&self) -> readback::Tables<'_> {
        readback::Tables {
            f32s: &self.outputs.f32s,
            u32s: &self.outputs.u32s,
            batch: &self.batch,
        }
    }

    /// What every submit of stages starts with: the pool rows staged since the last one copied
    /// into their places, and the rare work's queues emptied.
    fn begin_submit(&mut self, enc: &mut wgpu::CommandEncoder) {
        self.flush_pool_copies(enc);
        let counters = bytes_of::<u32>(schedule::RARE_QUEUES);
        enc.clear_buffer(&self.rare, 0, Some(counters));
    }

    /// Whether the device has timestamp queries ([`GpuStages::time_passes`]).
    pub fn has_timestamps(&self) -> bool {
        self.dev
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Seconds of device time each of `stages` takes, in order: each stage runs in a compute pass
    /// of its own with a timestamp written at its start and end, all in one submit (nothing is
    /// read back, so the next read copies the whole output table). `None` where the device has
    /// no timestamp queries (`wgpu::Features::TIMESTAMP_QUERY`); then time each stage as a submit
    /// of its own.
    pub fn time_passes(&mut self, stages: &[&str]) -> Result<Option<Vec<f64>>, SimError> {
        if !self.has_timestamps() || stages.is_empty() {
            return Ok(None);
        }
        let device = &self.dev.device;
        let count = 2 * stages.len() as u32;
        let set = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass times"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let bytes = 8 * u64::from(count);
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        let resolved = buffer(
            "pass times",
            wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        );
        let read = buffer(
            "pass times readback",
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("timed passes"),
        });
        self.begin_submit(&mut enc);
        // The queued rebuilds' one dispatch is timed with the last queueing stage timed.
        let queueing = self
            .last_queueing(stages)
            .and_then(|of| stages.iter().rposition(|s| *s == of));
        for (k, &stage) in (0u32..).zip(stages) {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(stage),
                timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                    query_set: &set,
                    beginning_of_pass_write_index: Some(2 * k),
                    end_of_pass_write_index: Some(2 * k + 1),
                }),
            });
            self.bind(&mut pass);
            for dispatch in plan(&[stage]) {
                self.sngnn_unread |= self.record(&mut pass, &dispatch)?;
            }
            if queueing == Some(k as usize) {
                self.record_queued_rebuild(&mut pass, stage)?;
            }
        }
        enc.resolve_query_set(&set, 0..count, &resolved, 0);
        enc.copy_buffer_to_buffer(&resolved, 0, &read, 0, bytes);
        self.dev.queue.submit([enc.finish()]);
        self.step_read.whole_table_next = true;
        // Nanoseconds per tick.
        let period = f64::from(self.dev.queue.get_timestamp_period());
        let mut seconds = Vec::with_capacity(stages.len());
        map_and_read(&self.dev, &read, bytes, |words| {
            let ticks = |i: usize| u64::from(words[2 * i]) | (u64::from(words[2 * i + 1]) << 32);
            for k in 0..stages.len() {
                let span = ticks(2 * k + 1).saturating_sub(ticks(2 * k));
                seconds.push(span as f64 * period * 1e-9);
            }
        })?;
        Ok(Some(seconds))
    }

    /// Set the batch's bind groups on `pass` (group 0 with the member mask table at mask 0, which
    /// a fused pass's dispatch replaces with its own).
    fn bind(&self, pass: &mut wgpu::ComputePass<'_>) {
        for (index, group) in (0u32..).zip(&self.bind_groups) {
            let offsets: &[u32] = if index == 0 { &[0] } else { &[] };
            pass.set_bind_group(index, group, offsets);
        }
    }

    /// Wait until the device has finished the work submitted so far.
    pub fn wait(&self) -> Result<(), SimError> {
        self.dev
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| SimError::Device(format!("GPU wait failed: {e}")))?;
        self.dev.take_errors()
    }

    /// The packed SNGNN graphs of every environment: the u32 regions and the f32 regions, one
    /// stride per environment (`sngnn::packed`); `None` without [`GpuStages::with_sngnn_graphs`].
    pub fn download_sngnn_graphs(&self) -> Result<Option<PackedGraphs>, SimError> {
        let Some((layout, gu, gf)) = &self.sngnn_graphs else {
            return Ok(None);
        };
        let u = self.read_words(gu, self.n_envs * layout.u32_stride())?;
        let f = self.read_words(gf, self.n_envs * layout.f32_stride())?;
        Ok(Some((u, f.into_iter().map(f32::from_bits).collect())))
    }

    /// The environments the last submit's regroupings and resets queued for their one obstacle
    /// rebuild (`schedule::REBUILD_QUEUE`), in the order they were queued: each at most once.
    pub fn queued_rebuilds(&self) -> Result<Vec<u32>, SimError> {
        let counters = self.read_words(&self.rare, schedule::RARE_QUEUES)?;
        let count = counters[schedule::REBUILD_QUEUE] as usize;
        if count > self.n_envs {
            return Err(SimError::Internal(format!(
                "the rebuild queue holds {count} environments of {}",
                self.n_envs
            )));
        }
        let first = schedule::RARE_QUEUES + schedule::REBUILD_QUEUE * self.n_envs;
        self.read_words_at(&self.rare, words_to_bytes(first), count)
    }

    /// Read the device's state back into `state` (same batch size and capacities).
    pub fn download_state(&self, state: &mut BatchState) -> Result<(), SimError> {
        let (f, u) = self.read_table(&self.state)?;
        state.unpack_in(wgsl::DEVICE_ORDER, &f, &u);
        Ok(())
    }

    /// Read the device's outputs back into `outputs` (same batch size and layout).
    pub fn download_outputs(&self, outputs: &mut Outputs) -> Result<(), SimError> {
        let (f, u) = self.read_table(&self.outputs)?;
        obs_payload::unpack(outputs, &f, &u);
        Ok(())
    }

    fn read_table(&self, t: &DeviceTable) -> Result<(Vec<f32>, Vec<u32>), SimError> {
        let f = self.read_words(&t.f32s, t.packed_f32.len())?;
        let u = self.read_words(&t.u32s, t.packed_u32.len())?;
        Ok((f.into_iter().map(f32::from_bits).collect(), u))
    }

    /// The first `n` 32-bit words of `src`.
    fn read_words(&self, src: &wgpu::Buffer, n: usize) -> Result<Vec<u32>, SimError> {
        self.read_words_at(src, 0, n)
    }

    /// `n` 32-bit words of `src` from byte `at` on.
    fn read_words_at(&self, src: &wgpu::Buffer, at: u64, n: usize) -> Result<Vec<u32>, SimError> {
        if n == 0 {
            return Ok(Vec::new());
        }
        let bytes = (n * 4) as u64;
        let mut enc = self
            .dev
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        enc.copy_buffer_to_buffer(src, at, &self.readback, 0, bytes);
        self.dev.queue.submit([enc.finish()]);
        let mut words = Vec::new();
        self.map_and_read(&self.readback, bytes, |w| words.extend_from_slice(w))?;
        Ok(words)
    }

    fn map_and_read(
        &self,
        buffer: &wgpu::Buffer,
        bytes: u64,
        read: impl FnOnce(&[u32]),
    ) -> Result<(), SimError> {
        map_and_read(&self.dev, buffer, bytes, read)
    }
}

/// One dispatch of a step: the pass that runs it (`schedule::pass_of`), and for a fused pass the mask
/// of the members it runs (`schedule::fused_passes`); `first` names its first stage in errors.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Dispatch<'a> {
    pass: &'a str,
    members: Option<u32>,
    first: &'a str,
}

impl Dispatch<'_> {
    /// Whether this dispatch runs stage `stage`.
    fn runs(&self, stage: &str) -> bool {
        match (self.members, schedule::fused_pass_of(stage)) {
            (Some(members), Some((pass, bit))) => pass == self.pass && members & (1 << bit) != 0,
            (None, None) => self.pass == stage,
            _ => false,
        }
    }
}

/// The dispatches that run `stages` in order: consecutive members of one fused pass, in the
/// pass's order, share a dispatch; any other stage is one of its own.
fn plan<'a>(stages: &[&'a str]) -> Vec<Dispatch<'a>> {
    let mut out: Vec<Dispatch<'a>> = Vec::with_capacity(stages.len());
    for &stage in stages {
        let Some((pass, bit)) = schedule::fused_pass_of(stage) else {
            out.push(Dispatch {
                pass: stage,
                members: None,
                first: stage,
            });
            continue;
        };
        if let Some(Dispatch {
            pass: last,
            members: Some(members),
            ..
        }) = out.last_mut()
            && *last == pass
            && *members >> bit == 0
        {
            *members |= 1 << bit;
            continue;
        }
        out.push(Dispatch {
            pass,
            members: Some(1 << bit),
            first: stage,
        });
    }
    out
}

/// The member masks of the fused passes as a uniform table: mask `m` (a `vec4<u32>` with `m`
/// first) at byte `m * stride`, the stride the device's dynamic uniform offsets allow.
fn member_mask_table(dev: &GpuDevice) -> (wgpu::Buffer, u32) {
    let stride = dev
        .device
        .limits()
        .min_uniform_buffer_offset_alignment
        .max(pipelines::DYNAMIC_UNIFORM_BYTES as u32);
    let words_per = (stride / 4) as usize;
    let mut words = vec![0u32; schedule::MEMBER_MASKS * words_per];
    for m in 0..schedule::MEMBER_MASKS {
        words[m * words_per] = m as u32;
    }
    (
        uniform_buffer(dev, "fused pass member masks", &words),
        stride,
    )
}

/// The pipelines of a pass: `main` and, for a stage with rare work ([`schedule::has_rare_work`]),
/// `queue_work` (dispatched before it, over every environment, to queue those `main` runs for); for
/// [`wgsl::OBS_ROWS_STAGE`], on a batch whose entity records are written apart, `records`
/// (dispatched after it: [`wgsl::OBS_RECORDS_ENTRY`]) and, on a device that stages observations,
/// `rows` (dispatched after those: the staged observation into its rows).
struct PassPipelines {
    queue: Option<wgpu::ComputePipeline>,
    main: wgpu::ComputePipeline,
    records: Option<wgpu::ComputePipeline>,
    rows: Option<wgpu::ComputePipeline>,
    /// The rebuild after `main` of a pass that regroups ([`schedule::regroups`]), and how it runs;
    /// that of a pass that resets ([`schedule::rebuilds_resets`]) where the batch's pool rows leave
    /// their obstacles to the device.
    rebuild: Option<(wgpu::ComputePipeline, Rebuild)>,
}

/// How a pass rebuilds the ORCA obstacles of its regrouped (or reset) environments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Rebuild {
    /// [`wgsl::REBUILD_ENTRY`]: one queued environment per lane, over `scratch`.
    PerLane,
    /// [`wgsl::REBUILD_IN_WORKGROUPS_ENTRY`]: one per workgroup, in workgroup memory; dispatched
    /// with a workgroup per environment of the batch, `GpuDevice::rebuild_workgroups` at most
    /// (the host does not know how many are queued), each taking every so-many-th queued one.
    InWorkgroups,
}

/// The ways a batch's passes run that choose their pipelines: how they rebuild obstacles,
/// whether the entity records of the observation are written apart ([`wgsl::OBS_RECORDS_ENTRY`]),
/// and whether the passes that reset rebuild the obstacles the pool's rows leave to the device
/// ([`schedule::rebuilds_resets`]).
#[derive(Debug, Clone, Copy)]
struct Ways {
    rebuild: Rebuild,
    records_apart: bool,
    obstacles_after_resets: bool,
}

/// A grid of at least `n` workgroups, and fewer than `n` + rows, in as few rows of at most
/// `per_dimension` as hold them: (columns, rows).
fn workgroup_grid(n: usize, per_dimension: u32) -> (u32, u32) {
    let n = u32::try_from(n.max(1)).unwrap_or(u32::MAX);
    let rows = n.div_ceil(per_dimension.max(1));
    (n.div_ceil(rows), rows)
}

/// A pass's pipelines, and how many of them getting them compiled.
type Built = Option<(PassPipelines, usize)>;

/// The pipelines of pass `pass` (`schedule::pass_of(stage)`) over the batch (`prelude`, bind `groups`) and how many of them
/// were compiled now: `None` for a network stage, whose pipelines [`GpuStages::attach_sngnn_net`]
/// adds. A shader that needs the SNGNN graphs ([`wgsl::needs_sngnn`]) gets
/// [`wgsl::sngnn_prelude`] and group 1; any other, group 0 alone, whether the batch has the
/// graphs or not. The functions of [`GpuDevice::leave_out`] that the pass defines return at once;
/// their names go into `left_out`.
fn build_pass(
    dev: &GpuDevice,
    stage: &'static str,
    pass: &'static str,
    groups: &[Vec<Binding>],
    prelude: &str,
    ways: Ways,
    left_out: &mut Vec<String>,
) -> Result<Built, SimError> {
    let has_sngnn = groups.len() > 1;
    let missing_graphs = || {
        SimError::Usage(format!(
            "stage {stage:?} needs the SNGNN graph buffers (GpuStages::with_sngnn_graphs)"
        ))
    };
    if stage != schedule::RESET_PASS {
        let Some(s) = crate::pipeline::stage(stage) else {
            return Err(SimError::Usage(format!(
                "{stage:?} is neither a stage of the step nor the reset pass"
            )));
        };
        if s.sngnn_reward_only && !has_sngnn {
            return Err(missing_graphs());
        }
        if s.shader == Shader::Network {
            return Ok(None);
        }
    }
    let mut needs_sngnn = false;
    for file in schedule::pass_files(pass) {
        let files = wgsl::resolve(&file).map_err(SimError::Usage)?;
        needs_sngnn |= files.iter().any(|f| wgsl::needs_sngnn(f));
    }
    if needs_sngnn && !has_sngnn {
        return Err(missing_graphs());
    }
    let (prelude, groups) = if needs_sngnn {
        (format!("{prelude}{}", wgsl::sngnn_prelude()), &groups[..2])
    } else {
        (prelude.to_owned(), &groups[..1])
    };
    let rebuilds_resets = ways.obstacles_after_resets && schedule::rebuilds_resets(pass);
    let mut src = if rebuilds_resets {
        wgsl::assemble_pass_rebuilding_resets(pass, &prelude)
    } else {
        wgsl::assemble_pass(pass, &prelude)
    }
    .map_err(SimError::Usage)?;
    if !dev.leave_out.is_empty() {
        let (out, found) = wgsl::with_functions_returning_at_once(&src, &dev.leave_out);
        src = out;
        left_out.extend(found.into_iter().map(String::from));
    }
    let (main, new) = dev.pipelines.pipeline(dev, pass, groups, &src, "main")?;
    let mut compiled = usize::from(new);
    let mut entry = |wanted: bool, name: &str| -> Result<_, SimError> {
        if !wanted {
            return Ok(None);
        }
        let (pipeline, new) = dev.pipelines.pipeline(dev, pass, groups, &src, name)?;
        compiled += usize::from(new);
        Ok(Some(pipeline))
    };
    let queue = entry(schedule::has_rare_work(stage), schedule::QUEUE_ENTRY)?;
    let observes = pass == schedule::pass_of(wgsl::OBS_ROWS_STAGE);
    let records = entry(observes && ways.records_apart, wgsl::OBS_RECORDS_ENTRY)?;
    let rows = entry(observes && dev.stage_observations, wgsl::OBS_ROWS_ENTRY)?;
    let rebuilds = schedule::regroups(pass) || rebuilds_resets;
    let rebuild = match (rebuilds, ways.rebuild) {
        (false, _) => None,
        (true, Rebuild::PerLane) => {
            entry(true, wgsl::REBUILD_ENTRY)?.map(|p| (p, Rebuild::PerLane))
        }
        (true, Rebuild::InWorkgroups) => {
            let moved = wgsl::with_obstacles_in_workgroup(&src).ok_or_else(|| {
                SimError::Internal(format!("pass {pass} has no ORCA obstacle library"))
            })?;
            let entry = wgsl::REBUILD_IN_WORKGROUPS_ENTRY;
            let (p, new) = dev.pipelines.pipeline(dev, pass, groups, &moved, entry)?;
            compiled += usize::from(new);
            Some((p, Rebuild::InWorkgroups))
        }
    };
    let pipelines = PassPipelines {
        queue,
        main,
        records,
        rows,
        rebuild,
    };
    Ok(Some((pipelines, compiled)))
}

#[cfg(test)]
mod tests {
    use super::backend::step_stages as step;
    use super::{Dispatch, plan};
    use crate::backend::schedule;

    fn passes<'a>(dispatches: &[Dispatch<'a>]) -> Vec<(&'a str, Option<u32>)> {
        dispatches.iter().map(|d| (d.pass, d.members)).collect()
    }

    /// A grid of `n` workgroups (the rebuild's: one per environment, at most the device's
    /// `rebuild_workgroups`), in rows of at most the device's workgroups per dimension: never
    /// fewer workgroups than `n`, less than a row more, never a dimension past the limit.
    #[test]
    fn a_workgroup_grid_covers_the_batch_within_the_limit() {
        use super::workgroup_grid;
        assert_eq!(workgroup_grid(65_536, 65_535), (32_768, 2));
        assert_eq!(workgroup_grid(100, 65_535), (100, 1));
        assert_eq!(workgroup_grid(0, 65_535), (1, 1));
        for (n, limit) in [(1_000_001, 65_535), (7, 3), (9, 3), (131_071, 65_535)] {
            let (x, y) = workgroup_grid(n, limit);
            assert!(x <= limit && y <= limit, "{n}, {limit}: {x} x {y}");
            let total = (x as usize) * (y as usize);
            assert!(
                total >= n && total < n + y as usize,
                "{n}, {limit}: {x} x {y}"
            );
        }
    }

    /// A step without SNGNN-v2 runs each fused pass in one dispatch with every member; eleven
    /// stages become three dispatches.
    #[test]
    fn a_step_runs_each_fused_pass_once() {
        let stages = step(false);
        let planned = plan(&stages);
        assert_eq!(
            passes(&planned),
            [
                ("begin_step", None),
                ("motion", Some(0b111)),
                ("crowd", Some(0b111)),
                ("formation", None),
                ("outcome", Some(0b1_1111)),
                ("social_events", None),
                ("autoreset", None),
            ]
        );
        assert_eq!(stages.len() - planned.len(), 11 - 3);
        for stage in stages {
            assert_eq!(
                planned.iter().filter(|d| d.runs(stage)).count(),
                1,
                "{stage}"
            );
        }
    }

    /// With SNGNN-v2's graph and network between `termination` and `reward`, the outcome pass
    /// runs twice, each time with the members on its side of them.
    #[test]
    fn stages_between_members_split_the_dispatch() {
        let planned = plan(&step(true));
        let outcome: Vec<Option<u32>> = planned
            .iter()
            .filter(|d| d.pass == "outcome")
            .map(|d| d.members)
            .collect();
        assert_eq!(outcome, [Some(0b11), Some(0b1_1100)]);
        let at = |pass: &str, first: &str| {
            planned
                .iter()
                .position(|d| d.pass == pass && d.first == first)
                .unwrap()
        };
        assert!(at("outcome", "contacts") < at("sngnn_graph", "sngnn_graph"));
        assert!(at("sngnn_score", "sngnn_score") < at("outcome", "reward"));
    }

    /// Members asked for out of their pass's order, or one stage alone, keep the order asked for.
    #[test]
    fn a_dispatch_never_reorders_stages() {
        assert_eq!(
            passes(&plan(&["group_velocities", "robot_motion", "shadow_robot"])),
            [("motion", Some(0b100)), ("motion", Some(0b11))]
        );
        assert_eq!(passes(&plan(&["metrics"])), [("outcome", Some(0b1000))]);
        assert_eq!(passes(&plan(&["reset"])), [("reset", None)]);
        let alone = plan(&["observation"]);
        assert!(alone[0].runs("observation") && !alone[0].runs("metrics"));
        assert_eq!(schedule::pass_of("observation"), "outcome");
    }
}
