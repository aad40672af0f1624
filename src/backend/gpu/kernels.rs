//! The kernels of a pass: its pipelines (`main`, the rare work's `queue_work`, the observation's
//! `records` and `rows`, the obstacle rebuild) compiled from the pass's assembled source for the
//! batch's paths, the fused passes' member masks, and the workgroup grid of a dispatch.

use super::device::GpuDevice;
use super::kit::uniform_buffer;
use super::pipelines;
use super::pipelines::Binding;
use crate::backend::{schedule, wgsl};
use crate::error::SimError;
use crate::pipeline::Shader;

/// The member masks of the fused passes as a uniform table: mask `m` (a `vec4<u32>` with `m`
/// first) at byte `m * stride`, the stride the device's dynamic uniform offsets allow.
pub(super) fn member_mask_table(dev: &GpuDevice) -> (wgpu::Buffer, u32) {
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
pub(super) struct PassPipelines {
    pub(super) queue: Option<wgpu::ComputePipeline>,
    pub(super) main: wgpu::ComputePipeline,
    pub(super) records: Option<wgpu::ComputePipeline>,
    pub(super) rows: Option<wgpu::ComputePipeline>,
    /// The rebuild after `main` of a pass that regroups ([`schedule::regroups`]), and how it runs;
    /// that of a pass that resets ([`schedule::rebuilds_resets`]) where the batch's pool rows leave
    /// their obstacles to the device.
    pub(super) rebuild: Option<(wgpu::ComputePipeline, Rebuild)>,
}

/// How a pass rebuilds the ORCA obstacles of its regrouped (or reset) environments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Rebuild {
    /// [`wgsl::REBUILD_ENTRY`]: one queued environment per lane, over `scratch`.
    PerLane,
    /// [`wgsl::REBUILD_IN_WORKGROUPS_ENTRY`]: one per workgroup, in workgroup memory; dispatched
    /// with a workgroup per environment of the batch, `GpuPaths::rebuild_workgroups` at most
    /// (the host does not know how many are queued), each taking every so-many-th queued one.
    InWorkgroups,
}

/// The ways a batch's passes run that choose their pipelines: how they rebuild obstacles,
/// whether the entity records of the observation are written apart ([`wgsl::OBS_RECORDS_ENTRY`]),
/// and whether the passes that reset rebuild the obstacles the pool's rows leave to the device
/// ([`schedule::rebuilds_resets`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct Ways {
    pub(super) rebuild: Rebuild,
    pub(super) records_apart: bool,
    pub(super) obstacles_after_resets: bool,
}

/// A grid of at least `n` workgroups, and fewer than `n` + rows, in as few rows of at most
/// `per_dimension` as hold them: (columns, rows).
pub(super) fn workgroup_grid(n: usize, per_dimension: u32) -> (u32, u32) {
    let n = u32::try_from(n.max(1)).unwrap_or(u32::MAX);
    let rows = n.div_ceil(per_dimension.max(1));
    (n.div_ceil(rows), rows)
}

/// A pass's pipelines, and how many of them getting them compiled.
pub(super) type Built = Option<(PassPipelines, usize)>;

/// The pipelines of pass `pass` (`schedule::pass_of(stage)`) over the batch (`prelude`, bind `groups`) and how many of them
/// were compiled now: `None` for a network stage, whose pipelines [`GpuStages::attach_sngnn_net`]
/// adds. A shader that needs the SNGNN graphs ([`wgsl::needs_sngnn`]) gets
/// [`wgsl::sngnn_prelude`] and group 1; any other, group 0 alone, whether the batch has the
/// graphs or not. The functions of [`GpuPaths::leave_out`] that the pass defines return at once;
/// their names go into `left_out`.
pub(super) fn build_pass(
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
    if !dev.paths.leave_out.is_empty() {
        let (out, found) = wgsl::with_functions_returning_at_once(&src, &dev.paths.leave_out);
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
    let rows = entry(
        observes && dev.paths.stage_observations,
        wgsl::OBS_ROWS_ENTRY,
    )?;
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
