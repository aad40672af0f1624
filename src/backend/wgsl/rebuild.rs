//! The ORCA obstacle rebuilds generated into the passes that regroup or reset environments: their
//! entry points (one environment a lane, or a workgroup's lanes on one environment with its working
//! memory in workgroup memory) and the sizes of that memory.

use super::WORKGROUP_SIZE;
use super::layout::ObstacleScratch;
use crate::backend::schedule::RESET_PASS;

/// The rebuild entry point (`regroups`, `rebuilds_resets`) that takes one queued
/// environment per lane, its working memory in the environment's region of `scratch`.
pub const REBUILD_ENTRY: &str = "rebuild";

/// The rebuild entry point that takes the queued environments a workgroup at a time, its working
/// memory in workgroup memory (built from [`with_obstacles_in_workgroup`]'s source; a dispatch of a
/// workgroup per environment of the batch, at most `GpuPaths::rebuild_workgroups`, workgroup `w`
/// of `W` taking queue entries `w`, `w + W`, ...), its first lane gathering the polygons and
/// keeping the tree's stack, every lane taking a share of each polygon, of each tree node's split
/// search and split, and of the store (`orca_obstacles_rebuild_on_lanes`): the
/// GPU backend's choice on hardware adapters (`GpuPaths::obstacles_in_workgroups`), where a
/// rebuild over `scratch` is a chain of dependent storage-buffer accesses (2.4 of exp2's 5.1 ms a
/// step on an H100), and in one lane the split search's quadratic loop was most of a rebuild (about
/// 0.4 ms on an H200). (llvmpipe ends the loops of an invocation after 65,535 iterations in all, so
/// there a workgroup must not take several large rebuilds; lavapipe rebuilds per lane, and tests
/// that force this path keep to small batches.)
pub const REBUILD_IN_WORKGROUPS_ENTRY: &str = "rebuild_in_workgroups";

/// A pass's two rebuild entry points over `target`, a WGSL function of `k`, the entry's index,
/// saying what its `k`th entry rebuilds: an environment, `ORCA_OBSTACLES_SKIP` (nothing, but
/// later entries may) or `NONE` (no entry from `k` on); `what` names the entries in the comment.
/// [`REBUILD_ENTRY`] takes an entry a lane; [`REBUILD_IN_WORKGROUPS_ENTRY`] an entry at a time
/// per workgroup, on all its lanes (`orca_obstacles_rebuild_on_lanes`).
pub(super) fn rebuild_entries(what: &str, target: &str) -> String {
    format!(
        "\n// The ORCA obstacle rebuilds of {what} (generated: src/backend/wgsl/rebuild.rs, \
         `rebuild_entries`).\n\
         @compute @workgroup_size(WORKGROUP_SIZE)\n\
         fn {REBUILD_ENTRY}(@builtin(global_invocation_id) gid: vec3<u32>) {{\n\
         \x20   let e = {target}(gid.x);\n\
         \x20   if (e < ORCA_OBSTACLES_SKIP) {{\n\
         \x20       orca_obstacles_rebuild_if_dirty(e);\n    }}\n}}\n\
         @compute @workgroup_size(WORKGROUP_SIZE)\n\
         fn {REBUILD_IN_WORKGROUPS_ENTRY}(\n\
         \x20   @builtin(workgroup_id) wid: vec3<u32>,\n\
         \x20   @builtin(num_workgroups) groups: vec3<u32>,\n\
         \x20   @builtin(local_invocation_index) lane: u32,\n) {{\n\
         \x20   let teams = groups.x * groups.y;\n\
         \x20   for (var k = wid.x + wid.y * groups.x; \
         orca_obstacles_rebuild_on_lanes({target}(k), lane); k += teams) {{}}\n}}\n"
    )
}

/// The two rebuild entry points of a pass that [`queues_rebuilds`], over the environments the
/// submit's regroupings and resets queued ([`REBUILD_QUEUE`]): the same in each such pass.
pub(super) fn queued_rebuild_entries() -> String {
    format!(
        "\nfn rebuild_target(k: u32) -> u32 {{\n    return rare_env(RARE_REBUILD, k);\n}}\n{}",
        rebuild_entries(
            "the environments the submit regrouped or reset",
            "rebuild_target"
        )
    )
}

/// The two rebuild entry points of pass `pass`, which [`rebuilds_resets`]: over the
/// [`REBUILD_QUEUE`] for the step's ([`queues_rebuilds`]), over the reset pass's mask (the
/// first action float non-zero) for it.
pub(super) fn reset_rebuild_entries(pass: &str) -> String {
    if pass != RESET_PASS {
        return queued_rebuild_entries();
    }
    let target = "    if (k >= batch.n_envs) {\n        return NONE;\n    }\n\
         \x20   if (actions[3u * k] != 0.0) {\n        return k;\n    }\n\
         \x20   return ORCA_OBSTACLES_SKIP;\n";
    format!(
        "\nfn rebuild_target(k: u32) -> u32 {{\n{target}}}\n{}",
        rebuild_entries(
            "the environments `main` reset from rows that leave them to the device",
            "rebuild_target"
        )
    )
}

/// Words of workgroup memory [`REBUILD_IN_WORKGROUPS_ENTRY`] takes in all (the obstacle region
/// and the lanes' shared words): 16 KiB, the workgroup memory every WebGPU adapter has (wgpu's
/// default `max_compute_workgroup_storage_size`).
pub const REBUILD_WORKGROUP_WORDS: usize = 4096;

/// Words of each side's mask of a tree node's edges in a rebuild on a workgroup's lanes (the
/// shader's `ORCA_OBSTACLES_MASK_WORDS`, which the prelude declares from this): a bit an edge, so a node of at most 32 times as many
/// edges. No obstacle region that fits [`OBSTACLES_IN_WORKGROUP_WORDS`] has that many vertices
/// (asserted below), and the split keys' fields of 10 bits hold every count and position below it.
pub const REBUILD_MASK_WORDS: usize = 12;

/// Words of workgroup memory the lanes of a rebuild share besides the obstacle region
/// (`orca_obstacles_rebuild_on_lanes`): the rebuild in hand and the node (two `vec2<u32>`), the
/// least split key, a count of each lane's share of a candidate's edges, and the two side masks.
pub const REBUILD_LANES_WORDS: usize = 2 + 2 + 1 + WORKGROUP_SIZE as usize + 2 * REBUILD_MASK_WORDS;

/// Words of workgroup memory [`REBUILD_IN_WORKGROUPS_ENTRY`] keeps an environment's obstacle
/// region in ([`ObstacleScratch`]): the rest of [`REBUILD_WORKGROUP_WORDS`]. Every shipped
/// config's region fits (stress, the largest, 3,348 words); a larger one stays in the `scratch`
/// buffer.
pub const OBSTACLES_IN_WORKGROUP_WORDS: usize = REBUILD_WORKGROUP_WORDS - REBUILD_LANES_WORDS;
// A region of as many vertices as the side masks hold does not fit workgroup memory.
const _: () = assert!(
    ObstacleScratch::for_vertices(32 * REBUILD_MASK_WORDS).words > OBSTACLES_IN_WORKGROUP_WORDS
);

/// The obstacle library's region function as `shaders/common/orca_obstacles.wgsl` writes it.
pub(super) const OBSTACLE_REGION_IN_SCRATCH: &str =
    "fn orca_obstacles_region(e: u32) -> u32 {\n    return e * batch.s_scratch;\n}\n";

/// `src`, a pass that `regroups` assembled by `assemble_pass`, with the obstacle library's
/// working memory (the polygon list, the processed set, the tree build's stack) in a workgroup
/// array of [`OBSTACLES_IN_WORKGROUP_WORDS`] words instead of the environment's region of
/// `scratch`: one dependent chain of accesses at the latency of workgroup memory rather than of
/// a storage buffer. Every `scratch[` of the source is rewritten, the slot permutations' too,
/// which that entry point never reaches. Sound for [`REBUILD_IN_WORKGROUPS_ENTRY`] alone, which
/// rebuilds one environment at a time per workgroup (its first lane writing the region, every
/// lane reading it between barriers), and because nothing in the region outlives the call that
/// fills it; never compile another entry point from it (lanes would share the array).
/// `None` when `src` has no obstacle library.
pub fn with_obstacles_in_workgroup(src: &str) -> Option<String> {
    if !src.contains(OBSTACLE_REGION_IN_SCRATCH) {
        return None;
    }
    let out = src
        .replacen(
            OBSTACLE_REGION_IN_SCRATCH,
            "fn orca_obstacles_region(e: u32) -> u32 {\n    return 0u;\n}\n",
            1,
        )
        .replace("scratch[", "obstacle_wg[");
    Some(format!(
        "{out}\n// The obstacle library's working memory (src/backend/wgsl/rebuild.rs, \
         `with_obstacles_in_workgroup`).\nvar<workgroup> obstacle_wg: array<u32, \
         {OBSTACLES_IN_WORKGROUP_WORDS}>;\n"
    ))
}
