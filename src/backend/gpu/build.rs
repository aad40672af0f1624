//! Making a batch's device data: the state, outputs, parameters, actions, queues and scratch
//! buffers, sized and checked against the device's limits, their bind groups, and the passes'
//! pipelines (`kernels`), in one scope that turns a device error into `SimError`.

use super::device::GpuDevice;
use super::kernels::{Rebuild, Ways, build_pass, member_mask_table};
use super::kit::{
    CreationScope, bind_kinds, bytes_of, check_binding, storage_buffer, uniform_buffer,
};
use super::pipelines::{Binding, Groups};
use super::pool_writes::{POOL_STAGING_ROWS, PoolScatter, obstacle_build, staging_buffer};
use super::readback::StepReadback;
use super::{GpuStages, SngnnBinding, readback};
use crate::backend::{obs_payload, schedule, wgsl};
use crate::error::SimError;
use crate::outputs::Outputs;
use crate::params::StepParams;
use crate::sngnn::packed::PackedLayout;
use crate::state::BatchState;

/// A packed table on the device: every f32 column in one storage buffer, every u32 column in
/// another, and the host copies they are packed from and read back into.
pub(super) struct DeviceTable {
    pub(super) f32s: wgpu::Buffer,
    pub(super) u32s: wgpu::Buffer,
    pub(super) packed_f32: Vec<f32>,
    pub(super) packed_u32: Vec<u32>,
}

impl DeviceTable {
    /// Buffers for a table packed into `packed_f32`/`packed_u32`, or why they do not fit.
    pub(super) fn new(
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

    pub(super) fn largest(&self) -> usize {
        self.packed_f32.len().max(self.packed_u32.len())
    }
}

/// The packed SNGNN graph buffers of `n_envs` environments at `layout`'s strides (u32, f32),
/// or why the adapter cannot bind them.
pub(super) fn sngnn_buffers(
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

/// The stages' working memory of `n_envs` environments (`wgsl::scratch_words`: ORCA's obstacles,
/// the slot permutations and, staged, the observation of `staged_obs_dim` floats), or why the
/// adapter cannot bind it.
pub(super) fn scratch_buffer(
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

impl GpuStages {
    /// [`GpuStages::build_in_scope`], with the device's errors on the way caught
    /// ([`CreationScope`]).
    pub(super) fn build(
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
    pub(super) fn build_in_scope(
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
        let pool_obstacles = obstacle_build(dev.paths.obstacles_after_resets);
        let pool_row_words = wgsl::pool_row_words(&state.columns(), &out_columns, pool_obstacles);
        // Two rows per environment: its next episode's and the one after it.
        let pool_bytes = bytes_of::<u32>(2 * n_envs * pool_row_words);
        check_binding(
            &dev,
            &format!("the reset pool of {n_envs} environments"),
            pool_bytes,
        )?;
        let pool = storage_buffer(&dev, "reset pool", pool_bytes);
        let obs_staged = dev.paths.stage_observations;
        let entity_records = if dev.paths.records_in_lanes {
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
        // Bind group 0 in the order of its declaration (`wgsl::BATCH_BINDINGS`), by name.
        let buffer_of = |name: &str| -> Result<&wgpu::Buffer, SimError> {
            Ok(match name {
                "params" => &params_buf,
                "sf" => &state_table.f32s,
                "su" => &state_table.u32s,
                "actions" => &actions,
                "outf" => &outputs_table.f32s,
                "outu" => &outputs_table.u32s,
                "pool" => &pool,
                "batch" => &batch,
                "scratch" => &scratch,
                "rare" => &rare,
                "pass_members" => &member_masks,
                other => {
                    return Err(SimError::Internal(format!(
                        "the batch has no buffer for binding {other}"
                    )));
                }
            })
        };
        let group0 = wgsl::BATCH_BINDINGS
            .iter()
            .map(|b| Ok((buffer_of(b.name)?, Binding::from(b.access))))
            .collect::<Result<Vec<_>, SimError>>()?;
        let storage = |read_only| Binding::Storage { read_only };
        let mut bound = vec![group0];
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
        if dev.paths.poison_orca_lists {
            prelude = wgsl::with_poisoned_orca_lists(&prelude);
        }
        if dev.paths.resets_in_workgroups {
            prelude = wgsl::with_resets_in_workgroups(&prelude);
        }
        // The regroupings on a workgroup's lanes where the device asks for it and their
        // workgroup memory fits.
        let regroups_in_workgroups = dev.paths.regroups_in_workgroups
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
        let rebuild = if dev.paths.obstacles_in_workgroups && fits {
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
                obstacles_after_resets: dev.paths.obstacles_after_resets,
            };
            let built = build_pass(&dev, stage, pass, &groups, &prelude, ways, &mut left_out)?;
            compiled += built.as_ref().map_or(0, |b| b.1);
            pipelines.push((pass, built.map(|b| b.0)));
        }
        let unknown: Vec<&str> = dev
            .paths
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
}
