//! The GPU backend: the batch state in device storage buffers and the stages of
//! [`crate::pipeline::STAGES`] as WGSL compute shaders (`shaders/<stage>.wgsl`).
//!
//! - [`device`]: finding and opening an adapter under the policy of docs/spec.md, adapters;
//!   [`paths`]: the ways a batch runs where two give the same bits ([`GpuPaths`]).
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
//!   Its parts: `build` makes its data, `kernels` its passes' pipelines, `step` plans, records
//!   and reads back runs of passes, `pool_writes` writes the reset pool's rows.
//! - [`GpuBackend`]: the whole step in one submit, with one readback of the outputs, and resets
//!   from a pool of rows the host generates off the step's critical path.

use build::DeviceTable;
use kernels::{PassPipelines, Rebuild};
use pool_writes::PoolScatter;

pub mod backend;
mod build;
pub mod device;
mod kernels;
pub(crate) mod kit;
pub mod paths;
pub(crate) mod pipelines;
pub(crate) mod pool_rows;
mod pool_writes;
pub(crate) mod readback;
pub mod sngnn_net;
pub(crate) mod spirv;
mod step;
mod timeline;
mod vulkan;

pub use backend::GpuBackend;
pub use device::{AdapterPolicy, AdapterSummary, GpuDevice, PATHS_VAR, SHADERS_VAR, list_adapters};
pub use paths::{DEFAULT_READBACK_PIECE_BYTES, DEFAULT_REBUILD_WORKGROUPS, GpuPaths};
pub use pool_writes::POOL_STAGING_ROWS;
pub use sngnn_net::GpuNet;

use std::sync::Arc;

use crate::backend::{obs_payload, schedule, wgsl};
use crate::error::SimError;
use crate::outputs::Outputs;
use crate::params::StepParams;
use crate::sngnn::history::TickGaps;
use crate::sngnn::model::Model;
use crate::sngnn::packed::PackedLayout;
use crate::sngnn::pieces::Tables;
use crate::state::BatchState;
use crate::systems::reset::ObstacleBuild;
use kit::{map_and_read, write_buffer_split};
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

/// A batch's state, outputs, parameters and actions on the device, and a pipeline per stage
/// shader.
pub struct GpuStages {
    dev: GpuDevice,
    n_envs: usize,
    /// Workgroups along an observation row of the observation pass's `rows` dispatch
    /// (`OBS_ROWS_TILE` floats each), made where the observation is staged.
    obs_row_tiles: u32,
    /// Entity records of a row, where they are written apart (`GpuPaths::records_in_lanes`),
    /// else 0: the rows of the observation pass's `records` dispatch.
    entity_records: u32,
    /// Whether the step's parameters ask for a whole view, which `records` needs to write
    /// anything (a limited sensor's records are the observing lane's).
    whole_view: bool,
    /// Whether `formation` and `social_events` take an environment a workgroup
    /// (`GpuPaths::regroups_in_workgroups`, where the workgroup memory fits).
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

    /// The adapter the stages run on.
    pub fn adapter(&self) -> &AdapterSummary {
        &self.dev.adapter
    }

    /// The adapter, and the ways taken: whether the pipelines run the backend's own SPIR-V
    /// (`spirv`: the ORCA lists not zeroed), with its storage-buffer bounds checked by the driver
    /// or clamped in the shaders (`spirv::BufferBounds`), or the WGSL as wgpu compiles it; how
    /// the observations are written (`GpuPaths::stage_observations`) and their entity records
    /// (`GpuPaths::records_in_lanes`, where the batch's rows have any), the resets run
    /// (`GpuPaths::resets_in_workgroups`), the obstacles are rebuilt
    /// (`GpuPaths::obstacles_in_workgroups`, where the batch's passes rebuild any) and a reset's
    /// obstacles are built (`GpuPaths::obstacles_after_resets`) and the memory the readback is
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
        let observations = if self.dev.paths.stage_observations {
            "staged through workgroup memory"
        } else {
            "written in place"
        };
        let resets = if self.dev.paths.resets_in_workgroups {
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
        let left_out = if self.dev.paths.leave_out.is_empty() {
            String::new()
        } else {
            format!(
                "; DIAGNOSIS, results wrong: functions left out: {}",
                self.dev.paths.leave_out.join(", ")
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
        let submitted = if self.dev.paths.readback_before_host_work {
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

    /// Whether the device has timestamp queries ([`GpuStages::time_passes`]).
    pub fn has_timestamps(&self) -> bool {
        self.dev
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
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
