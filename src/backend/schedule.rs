//! The GPU step's schedule, derived from the step's declaration (`pipeline::STAGES` and each
//! stage's `GpuPlan`): the passes the backend compiles (fused passes, stages alone, the reset
//! pass), the files of each, the rare-work queues, and which passes regroup or reset and so queue
//! ORCA obstacle rebuilds. No wgpu and no WGSL text here: `backend::wgsl` assembles the passes'
//! sources, `backend::gpu` records them.

use crate::pipeline::{FusedPass, GpuPlan};

/// The one shader at the top of `shaders/` that is not a stage of [`crate::pipeline::STAGES`]:
/// the masked reset of `Backend::reset`, a pass the GPU backend runs alone.
pub const RESET_PASS: &str = "reset";

/// Whether pass `pass` is a stage's whose rare work runs out of the hot pass
/// (`pipeline::GpuPlan::rare_work`: the resets of `begin_step` and `autoreset`, the regroupings
/// and obstacle rebuilds of `formation` and `social_events`): its shader has a second entry point,
/// [`QUEUE_ENTRY`], dispatched before `main` over every environment, which queues the
/// environments that have something to do this step (`rare_push(RARE_<STAGE>, e)`); `main` then
/// runs with one lane per queued environment (`rare_env(RARE_<STAGE>, lane)`), so a warp's lanes
/// all do the rare work instead of waiting for the one lane in 32 that does. The queues are the
/// `rare` binding: a counter per stage (`pipeline::rare_queue`), then a list of `n_envs`
/// environments per stage; the counters are cleared before every submit.
pub fn has_rare_work(pass: &str) -> bool {
    plan_of(pass).is_some_and(|plan| plan.rare_work)
}

/// The GPU plan of the stage named `pass`, where a stage is.
fn plan_of(pass: &str) -> Option<GpuPlan> {
    crate::pipeline::stage(pass).map(|s| s.gpu)
}

/// The entry point of a shader with rare work ([`has_rare_work`]) that queues its environments.
pub const QUEUE_ENTRY: &str = "queue_work";

/// Whether pass `pass`'s `main` regroups environments (`pipeline::GpuPlan::regroups`:
/// `regroup_canonicalize` in `shaders/common/regroup.wgsl`), leaving their ORCA obstacles to
/// rebuild: each regrouped environment is queued once a submit (`RARE_REBUILD`,
/// [`REBUILD_QUEUE`]), and one dispatch of a third entry point, generated (`rebuild_entries`),
/// rebuilds them all after the submit's last stage, with the resets' ([`queues_rebuilds`]; the
/// GPU backend's `record_queued_rebuild`, after the step's readback copies where a step is read
/// back), before anything reads the `ov_*` columns (only the ORCA velocities of the next step's
/// `motion` and `crowd` do). One rebuild per environment, after its last regrouping, gives the
/// columns the CPU's stages leave, since a rebuild depends on the obstacles alone: the CPU
/// rebuilds inside each regrouping, and the second of two in a step replaces the first's.
pub fn regroups(pass: &str) -> bool {
    plan_of(pass).is_some_and(|plan| plan.regroups)
}

/// The rare-work queue of the environments whose obstacles the passes that [`queues_rebuilds`]
/// left to rebuild (`RARE_REBUILD`), after the queues of the stages with rare work: an
/// environment is pushed when its `obstacles_dirty` becomes 1, so at most once a submit (no
/// environment ends a submit dirty).
pub const REBUILD_QUEUE: usize = crate::pipeline::RARE_WORK_STAGES;

/// Whether pass `pass`'s rebuilds wait in the [`REBUILD_QUEUE`] for the submit's one rebuild
/// dispatch (`pipeline::GpuPlan::queues_rebuilds`): the passes that [`regroups`], and the step's
/// passes that reset from the pool where the pool's rows leave their obstacles to the device. A
/// reset of `begin_step` (NEXT_STEP) takes no dynamics in its step and one of `autoreset`
/// (SAME_STEP) ends it, so neither environment's obstacles are read before the next step's ORCA
/// velocities, as after a regrouping; a SAME_STEP reset of an environment regrouped in the same
/// step is queued once (`pool_reset_queue_rebuild`). The reset pass, a submit of its own,
/// rebuilds after its `main`.
pub fn queues_rebuilds(pass: &str) -> bool {
    plan_of(pass).is_some_and(|plan| plan.queues_rebuilds())
}

/// Queues of the `rare` binding: one per stage with rare work, and the [`REBUILD_QUEUE`].
pub const RARE_QUEUES: usize = crate::pipeline::RARE_WORK_STAGES + 1;

/// Whether pass `pass` resets environments from the reset pool (`pipeline::GpuPlan::resets`, and
/// the reset pass): where the pool's rows leave their ORCA obstacles to the device
/// (`GpuPaths::obstacles_after_resets`, `systems::reset::ObstacleBuild::Deferred`), each is
/// assembled with the obstacle library and the two rebuild entry points (`wgsl::REBUILD_ENTRY`,
/// `wgsl::REBUILD_IN_WORKGROUPS_ENTRY`; `wgsl::assemble_pass_rebuilding_resets`): `begin_step` and
/// `autoreset` queue the environments they reset with the regroupings' for the submit's one rebuild
/// after its stages ([`queues_rebuilds`], [`REBUILD_QUEUE`]); the reset pass rebuilds its masked
/// environments after its `main`. Nothing reads the `ov_*` columns or their count between a reset
/// and the rebuild after it (the copy leaves the old ones in place: `wgsl::POOL_OBSTACLE_COLUMNS`;
/// a reset environment takes no dynamics until the next step).
pub fn rebuilds_resets(pass: &str) -> bool {
    pass == RESET_PASS || plan_of(pass).is_some_and(|plan| plan.resets)
}

/// The passes that [`rebuilds_resets`]: the step's in [`crate::pipeline::STAGES`] order, then the
/// reset pass.
pub fn reset_passes() -> Vec<&'static str> {
    let mut out: Vec<&'static str> = crate::pipeline::STAGES
        .iter()
        .filter(|s| s.gpu.resets)
        .map(|s| s.name)
        .collect();
    out.push(RESET_PASS);
    out
}

/// Words of the `rare` binding for `n_envs` environments: the counters, then the lists.
pub fn rare_work_words(n_envs: usize) -> usize {
    RARE_QUEUES * (1 + n_envs)
}

/// The fused passes (`pipeline::FusedPass`) as the GPU backend compiles them: a member's file
/// defines `fn stage_<name>(e: u32)` for an environment that steps, and no `main`; the pass's
/// `main` (generated: `wgsl::assemble_pass`) skips the lanes past the batch and the environments
/// that do not step, then calls each member whose bit (its index among the pass's stages) is set in
/// the dispatch's member mask, `pass_members` (binding 10: the mask `m` is the entry at dynamic
/// offset `m` times the table's stride, [`MEMBER_MASKS`] entries). So a step runs a pass's members
/// in one dispatch where no other stage comes between them (SNGNN-v2's graph and network come
/// between `termination` and `reward`), and a test or a timing runs one member alone, with the same
/// pipeline.
///
/// A pass holds at most [`MAX_ORCA_STAGES_PER_PASS`] stages that run ORCA.
pub fn fused_passes() -> impl Iterator<Item = (&'static str, Vec<&'static str>)> {
    FusedPass::ALL
        .into_iter()
        .map(|pass| (pass.name(), pass.members().map(|s| s.name).collect()))
}

/// The most stages that run ORCA (`orca_world_velocity`: `shadow_robot`, `group_velocities`,
/// `human_motion`) in one fused pass. NVIDIA's driver (580.159, H100) fails to compile a pipeline
/// with all three, from naga's SPIR-V as from the backend's own (`VK_ERROR_UNKNOWN`, which loses
/// the wgpu device); each alone, and the first two together, compile. Each ORCA call inlines its
/// own neighbour and line lists, about 8 KB of private memory per lane.
pub const MAX_ORCA_STAGES_PER_PASS: usize = 2;

/// The most members a fused pass has ([`fused_passes`]): a member mask has this many bits.
pub const MAX_FUSED_MEMBERS: usize = 5;

/// Entries of the member-mask table (binding 10): one per mask of [`MAX_FUSED_MEMBERS`] bits.
pub const MEMBER_MASKS: usize = 1 << MAX_FUSED_MEMBERS;

/// The fused pass stage `stage` runs in, and its member index there (its bit in a member mask).
pub fn fused_pass_of(stage: &str) -> Option<(&'static str, u32)> {
    crate::pipeline::fused_member(stage).map(|(pass, bit)| (pass.name(), bit))
}

/// The pass that runs stage `stage` (or the reset pass): its fused pass, or itself.
pub fn pass_of(stage: &str) -> &str {
    fused_pass_of(stage).map_or(stage, |(pass, _)| pass)
}

/// The files of pass `pass` under `shaders/`: its members' for a fused pass, else `<pass>.wgsl`.
pub fn pass_files(pass: &str) -> Vec<String> {
    match FusedPass::named(pass) {
        Some(fused) => fused.members().map(|s| s.shader_file()).collect(),
        None => vec![format!("{pass}.wgsl")],
    }
}

/// Every pass the GPU backend compiles from `shaders/` with the batch prelude: the fused passes,
/// then each stage of a batch shader that is in none, then the reset pass.
pub fn passes() -> Vec<&'static str> {
    let mut out: Vec<&'static str> = FusedPass::ALL.iter().map(|p| p.name()).collect();
    out.extend(
        crate::pipeline::STAGES
            .iter()
            .filter(|s| {
                s.shader == crate::pipeline::Shader::Batch && fused_pass_of(s.name).is_none()
            })
            .map(|s| s.name),
    );
    out.push(RESET_PASS);
    out
}
