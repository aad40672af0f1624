//! The WGSL sources of the GPU backend, embedded in the library, and how a stage's shader is
//! assembled: the batch prelude (generated from the state's column list, the `StepParams`
//! declaration and the Rust constants the shaders share, so no offset, stride, struct member or
//! shared constant is written twice), the common libraries the stage file requires, then the
//! stage file.
//!
//! A file names what it builds on in header lines `// requires: <path>` (relative to `shaders/`)
//! before its first non-comment line; requirements are prepended recursively, each once,
//! dependencies first. Stage files are `shaders/<stage>.wgsl`, named after their Rust twin in
//! `src/systems/`, with one environment per invocation. What the device compiles is a pass
//! (`schedule::passes`): a stage's file with its entry point `main`, or a fused pass
//! (`schedule::fused_passes`), whose members' files each define `fn stage_<name>(e: u32)` and whose
//! `main` is generated ([`assemble_pass`]).
//!
//! This module is plain text work (no wgpu), so the naga tests can assemble and validate the
//! shaders without the `gpu` feature or a device.

use super::schedule::{
    RARE_QUEUES, REBUILD_QUEUE, RESET_PASS, pass_files, rebuilds_resets, regroups,
};
use crate::pipeline::FusedPass;
use crate::state::columns::{Elem, ElementOrder};
use crate::systems::reset::ObstacleBuild;

/// Every WGSL file under `shaders/`, by path relative to it.
pub const FILES: &[(&str, &str)] = &[
    (
        "common/math.wgsl",
        include_str!("../../shaders/common/math.wgsl"),
    ),
    (
        "common/rng.wgsl",
        include_str!("../../shaders/common/rng.wgsl"),
    ),
    (
        "common/geometry.wgsl",
        include_str!("../../shaders/common/geometry.wgsl"),
    ),
    (
        "common/world.wgsl",
        include_str!("../../shaders/common/world.wgsl"),
    ),
    (
        "common/motion.wgsl",
        include_str!("../../shaders/common/motion.wgsl"),
    ),
    (
        "common/orca.wgsl",
        include_str!("../../shaders/common/orca.wgsl"),
    ),
    (
        "robot_motion.wgsl",
        include_str!("../../shaders/robot_motion.wgsl"),
    ),
    (
        "common/perception.wgsl",
        include_str!("../../shaders/common/perception.wgsl"),
    ),
    (
        "common/sfm.wgsl",
        include_str!("../../shaders/common/sfm.wgsl"),
    ),
    (
        "common/orca_world.wgsl",
        include_str!("../../shaders/common/orca_world.wgsl"),
    ),
    (
        "common/orca_obstacles.wgsl",
        include_str!("../../shaders/common/orca_obstacles.wgsl"),
    ),
    (
        "shadow_robot.wgsl",
        include_str!("../../shaders/shadow_robot.wgsl"),
    ),
    (
        "group_velocities.wgsl",
        include_str!("../../shaders/group_velocities.wgsl"),
    ),
    (
        "common/measures.wgsl",
        include_str!("../../shaders/common/measures.wgsl"),
    ),
    (
        "termination.wgsl",
        include_str!("../../shaders/termination.wgsl"),
    ),
    ("reward.wgsl", include_str!("../../shaders/reward.wgsl")),
    ("metrics.wgsl", include_str!("../../shaders/metrics.wgsl")),
    (
        "observation.wgsl",
        include_str!("../../shaders/observation.wgsl"),
    ),
    (
        "group_motion.wgsl",
        include_str!("../../shaders/group_motion.wgsl"),
    ),
    ("contacts.wgsl", include_str!("../../shaders/contacts.wgsl")),
    (
        "common/pool_reset.wgsl",
        include_str!("../../shaders/common/pool_reset.wgsl"),
    ),
    (
        "begin_step.wgsl",
        include_str!("../../shaders/begin_step.wgsl"),
    ),
    (
        "autoreset.wgsl",
        include_str!("../../shaders/autoreset.wgsl"),
    ),
    ("reset.wgsl", include_str!("../../shaders/reset.wgsl")),
    (
        "sngnn_score.wgsl",
        include_str!("../../shaders/sngnn_score.wgsl"),
    ),
    (
        "human_motion.wgsl",
        include_str!("../../shaders/human_motion.wgsl"),
    ),
    ("goals.wgsl", include_str!("../../shaders/goals.wgsl")),
    (
        "common/place.wgsl",
        include_str!("../../shaders/common/place.wgsl"),
    ),
    (
        "common/goal_sampling.wgsl",
        include_str!("../../shaders/common/goal_sampling.wgsl"),
    ),
    (
        "common/regroup.wgsl",
        include_str!("../../shaders/common/regroup.wgsl"),
    ),
    (
        "social_events.wgsl",
        include_str!("../../shaders/social_events.wgsl"),
    ),
    (
        "formation.wgsl",
        include_str!("../../shaders/formation.wgsl"),
    ),
    (
        "common/sngnn_frame.wgsl",
        include_str!("../../shaders/common/sngnn_frame.wgsl"),
    ),
    (
        "common/sngnn_graph_build.wgsl",
        include_str!("../../shaders/common/sngnn_graph_build.wgsl"),
    ),
    (
        "sngnn_graph.wgsl",
        include_str!("../../shaders/sngnn_graph.wgsl"),
    ),
];

/// The rebuild entry point ([`regroups`], [`rebuilds_resets`]) that takes one queued
/// environment per lane, its working memory in the environment's region of `scratch`.
pub const REBUILD_ENTRY: &str = "rebuild";

/// The rebuild entry point that takes the queued environments a workgroup at a time, its working
/// memory in workgroup memory (built from [`with_obstacles_in_workgroup`]'s source; a dispatch of a
/// workgroup per environment of the batch, at most `GpuDevice::rebuild_workgroups`, workgroup `w`
/// of `W` taking queue entries `w`, `w + W`, ...), its first lane gathering the polygons and
/// keeping the tree's stack, every lane taking a share of each polygon, of each tree node's split
/// search and split, and of the store (`orca_obstacles_rebuild_on_lanes`): the
/// GPU backend's choice on hardware adapters (`GpuDevice::obstacles_in_workgroups`), where a
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
fn rebuild_entries(what: &str, target: &str) -> String {
    format!(
        "\n// The ORCA obstacle rebuilds of {what} (generated: src/backend/wgsl.rs, \
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
fn queued_rebuild_entries() -> String {
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
fn reset_rebuild_entries(pass: &str) -> String {
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
/// shader's `ORCA_OBSTACLES_MASK_WORDS`): a bit an edge, so a node of at most 32 times as many
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
const OBSTACLE_REGION_IN_SCRATCH: &str =
    "fn orca_obstacles_region(e: u32) -> u32 {\n    return e * batch.s_scratch;\n}\n";

/// `src`, a pass that [`regroups`] assembled by [`assemble_pass`], with the obstacle library's
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
        "{out}\n// The obstacle library's working memory (src/backend/wgsl.rs, \
         `with_obstacles_in_workgroup`).\nvar<workgroup> obstacle_wg: array<u32, \
         {OBSTACLES_IN_WORKGROUP_WORDS}>;\n"
    ))
}

/// The entry point `main` of a fused pass with `members` ([`fused_passes`]).
fn fused_entry(pass: &str, members: &[&str]) -> String {
    let mut out = format!(
        "// ---- generated by src/backend/wgsl.rs: the entry point of fused pass `{pass}`\n\
         @compute @workgroup_size(WORKGROUP_SIZE)\n\
         fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{\n\
         \x20   let e = gid.x;\n\
         \x20   if (e >= batch.n_envs || su[batch.c_stepping + e] == 0u) {{\n\
         \x20       return;\n\
         \x20   }}\n\
         \x20   let members = pass_members.x;\n"
    );
    for (bit, m) in members.iter().enumerate() {
        out.push_str(&format!(
            "    if ((members & {}u) != 0u) {{\n        stage_{m}(e);\n    }}\n",
            1u32 << bit
        ));
    }
    out.push_str("}\n");
    out
}

/// The label of the GPU backend's finished-rows pass, a shader generated from the output columns
/// ([`finished_rows_shader`]), not a file of `shaders/`.
pub const FINISHED_ROWS_PASS: &str = "finished_rows";

/// The label of the GPU backend's pass that moves the reset pool's staged rows into their places
/// ([`pool_scatter_shader`]), not a file of `shaders/`.
pub const POOL_SCATTER_PASS: &str = "pool_scatter";

/// Words of a run in the pool scatter's list ([`pool_scatter_shader`]): its first word in the
/// staging buffer, its first word in the pool, and its words.
pub const POOL_RUN_WORDS: usize = 3;

/// Most words a workgroup of the pool scatter copies ([`pool_scatter_shader`]): a longer run of
/// rows is copied in pieces of this many words. A batch's first rows are one run (exp2 at 65,536
/// environments: 194 MB), which one workgroup would copy at a few warps' pace; and llvmpipe ends
/// an invocation's loops after 65,535 iterations in all, which a lane of such a workgroup would
/// pass (here a lane loops 32 times).
pub const POOL_SCATTER_PIECE_WORDS: usize = 32 * WORKGROUP_SIZE as usize;

/// The pool scatter pass ([`POOL_SCATTER_PASS`]): the runs of rows the host staged in one queue
/// write (`GpuStages::stage_pool_rows`) copied into their places in the reset pool, a workgroup a
/// piece of a run (at most [`POOL_SCATTER_PIECE_WORDS`]; in rows of workgroups past a
/// dimension's limit), its lanes a word each in turn. The workgroups may copy in any order: no
/// two pieces of one dispatch go to the same place (`GpuStages::stage_pool_rows`). One
/// dispatch where a `copy_buffer_to_buffer` per run cost about 0.7 µs of the host's time each in
/// wgpu's encoding (about 650 runs a step at 65,536 exp2 environments: 0.44 ms a step on the
/// 2-vCPU machine, against 0.04 ms for the dispatch and its list). Bindings: `staged` (read),
/// `runs` (read: the count, then [`POOL_RUN_WORDS`] words a run) and `pool`.
pub fn pool_scatter_shader(last_first: bool) -> String {
    // A test's (`GpuDevice::scatter_last_first`): workgroup `r` takes the copy counted from the
    // end.
    let entry = if last_first { "runs[0] - 1u - r" } else { "r" };
    format!(
        "// Generated by src/backend/wgsl.rs (pool_scatter_shader).\n\
         const WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;\n\
         const RUN_WORDS: u32 = {POOL_RUN_WORDS}u;\n\
         @group(0) @binding(0) var<storage, read> staged: array<u32>;\n\
         @group(0) @binding(1) var<storage, read> runs: array<u32>;\n\
         @group(0) @binding(2) var<storage, read_write> pool: array<u32>;\n\
         @compute @workgroup_size(WORKGROUP_SIZE)\n\
         fn main(\n\
         \x20   @builtin(workgroup_id) wid: vec3<u32>,\n\
         \x20   @builtin(num_workgroups) groups: vec3<u32>,\n\
         \x20   @builtin(local_invocation_index) lane: u32,\n\
         ) {{\n\
         \x20   let r = wid.x + wid.y * groups.x;\n\
         \x20   if (r >= runs[0]) {{\n\
         \x20       return;\n\
         \x20   }}\n\
         \x20   let k = {entry};\n\
         \x20   let src = runs[1u + RUN_WORDS * k];\n\
         \x20   let dst = runs[2u + RUN_WORDS * k];\n\
         \x20   let words = runs[3u + RUN_WORDS * k];\n\
         \x20   for (var w = lane; w < words; w += WORKGROUP_SIZE) {{\n\
         \x20       pool[dst + w] = staged[src + w];\n\
         \x20   }}\n\
         }}\n"
    )
}

/// Whether `shaders/<path>` is a stage shader with bindings of its own and no batch prelude
/// ([`crate::pipeline::Shader::Network`]: SNGNN-v2's network); [`assemble_standalone`] builds
/// those.
pub fn is_standalone(path: &str) -> bool {
    crate::pipeline::STAGES
        .iter()
        .any(|s| s.shader == crate::pipeline::Shader::Network && s.shader_file() == path)
}

/// Whether `shaders/<path>` needs [`sngnn_prelude`]: the SNGNN stages with the batch prelude and
/// their libraries.
pub fn needs_sngnn(path: &str) -> bool {
    path.contains("sngnn") && !is_standalone(path)
}

/// Invocations per workgroup of the stage shaders (one environment each).
pub const WORKGROUP_SIZE: u32 = 64;

/// The source of `shaders/<path>`.
pub fn source(path: &str) -> Option<&'static str> {
    FILES.iter().find(|(p, _)| *p == path).map(|(_, s)| *s)
}

/// The `// requires: <path>` lines of a file's leading comment block.
pub fn requires(src: &str) -> Vec<&str> {
    src.lines()
        .map(str::trim)
        .take_while(|l| l.is_empty() || l.starts_with("//"))
        .filter_map(|l| l.strip_prefix("// requires:"))
        .map(str::trim)
        .collect()
}

/// `path` and everything it requires, dependencies first, each once.
pub fn resolve(path: &str) -> Result<Vec<&'static str>, String> {
    fn visit(
        path: &str,
        order: &mut Vec<&'static str>,
        visiting: &mut Vec<String>,
    ) -> Result<(), String> {
        let Some((name, src)) = FILES.iter().find(|(p, _)| *p == path) else {
            return Err(format!(
                "shaders/{path} is not embedded (backend::wgsl::FILES)"
            ));
        };
        if order.contains(name) {
            return Ok(());
        }
        if visiting.iter().any(|v| v == path) {
            return Err(format!("require cycle through shaders/{path}"));
        }
        visiting.push(path.to_owned());
        for r in requires(src) {
            visit(r, order, visiting)?;
        }
        visiting.pop();
        order.push(name);
        Ok(())
    }
    let mut order = Vec::new();
    visit(path, &mut order, &mut Vec::new())?;
    Ok(order)
}

/// The files `paths` need, each once, in the order of [`resolve`] over each path in turn.
fn resolve_each(paths: &[String]) -> Result<Vec<&'static str>, String> {
    let mut order: Vec<&'static str> = Vec::new();
    for path in paths {
        for f in resolve(path)? {
            if !order.contains(&f) {
                order.push(f);
            }
        }
    }
    Ok(order)
}

/// A table's columns as [`crate::state::BatchState::columns`] lists them: name, element kind,
/// stride.
pub type Columns<'a> = &'a [(&'static str, Elem, usize)];

/// The element order of the state's slot columns on the device ([`ElementOrder`]).
pub const DEVICE_ORDER: ElementOrder = ElementOrder::SlotMajor;

/// The slot kinds of a state table (every kind but `env`, whose columns hold one element per
/// environment and so have one order), each with its capacity, in declaration order.
pub fn slot_kinds(state: Columns<'_>) -> Vec<(&'static str, usize)> {
    let mut kinds: Vec<(&'static str, usize)> = Vec::new();
    for &(col, _, cap) in state {
        if let Some(kind) = kind_of(col).filter(|&k| k != "env") {
            if !kinds.iter().any(|&(k, _)| k == kind) {
                kinds.push((kind, cap));
            }
        }
    }
    kinds
}

/// The index helpers of the state's slot kinds: `at_<kind>(e, slot)`, the element of
/// environment `e`'s `slot` from a column's first word, and `slot_<kind>(e, i)`, its inverse.
fn slot_index_functions(state: Columns<'_>) -> String {
    slot_kinds(state)
        .iter()
        .map(|(kind, _)| {
            format!(
                "fn at_{kind}(e: u32, slot: u32) -> u32 {{\n    \
                 return e * batch.e_{kind} + slot * batch.k_{kind};\n}}\n\
                 fn slot_{kind}(e: u32, i: u32) -> u32 {{\n    \
                 return (i - e * batch.e_{kind}) / batch.k_{kind};\n}}\n"
            )
        })
        .collect()
}

/// The batch layout the shaders read at run time, as the uniform `batch` (binding 7) of
/// [`prelude`]: `n_envs`; for each state column its first word `c_<name>` in the packed buffer
/// of its kind (`sf` for f32, `su` for u32) and its capacity `s_<name>` (slots per environment);
/// for each slot kind of the state its steps `e_<kind>` and `k_<kind>` in [`DEVICE_ORDER`]
/// (element `slot` of environment `e` is at `c + e * e_<kind> + slot * k_<kind>`, which the
/// prelude's `at_<kind>(e, slot)` computes; an `env` column's element is at `c + e`); the output
/// columns as `co_<name>`/`so_<name>` in `outf`/`outu` (environment-major: element `k` of
/// environment `e` at `co + e * so + k`, the rows the host reads); the observation layout
/// (`obs_dim`, `obs_robot`, and per entity type `obs_offset_<type>`, `obs_capacity_<type>`, per
/// interaction kind `pairs_<kind>`); the reset pool's `pool_row` (words per row),
/// `pool_observation` (the observation's first word in a row) and `pool_obstacles` (1 when a row
/// holds the ORCA obstacles: [`BatchLayout::with_pool_obstacles`]); the `scratch` region of an
/// environment (`s_scratch`, [`scratch_region_words`]), the obstacle library's part of it
/// (`obstacle_words`, `x_obstacle_*`: [`ObstacleScratch`]) and the slot permutations' part of
/// each kind (`x_permute_<kind>`, where its old slots start), `x_obs_staged`, where the staged
/// observation starts in it ([`scratch_words`]), `obs_staged` (1 when the observation is staged)
/// and `obs_records_apart` (1 when [`OBS_RECORDS_ENTRY`] writes the entity records); and the
/// SNGNN-v2 sizes (`sn_*`, 0 without the SNGNN graphs). None of it is compiled into a shader, so
/// one compiled pipeline serves every batch size and every config of the same [`SizeClasses`].
/// The field names are the same for every batch (the column list is fixed), so the WGSL struct is
/// too.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BatchLayout {
    fields: Vec<(String, u32)>,
}

/// The SNGNN-v2 part of a [`BatchLayout`]: the packed graphs' layout, with the state's
/// capacities.
#[derive(Debug, Clone, Copy)]
pub struct SngnnSizes<'a> {
    /// The state's capacities (frame history, entities, walls).
    pub caps: &'a crate::state::Caps,
    /// The packed graph layout.
    pub graphs: &'a crate::sngnn::packed::PackedLayout,
}

impl BatchLayout {
    /// The layout of a batch of `n_envs` environments with these tables, observation layout and,
    /// with the SNGNN graphs, their sizes.
    ///
    /// # Panics
    /// If a count does not fit a `u32` (the GPU backend checks buffer sizes against the
    /// adapter's limits long before).
    #[expect(
        clippy::expect_used,
        reason = "layout values are buffer sizes, bounded by the adapter's u32 limits"
    )]
    pub fn new(
        n_envs: usize,
        state: Columns<'_>,
        outputs: Columns<'_>,
        obs: &crate::spec::ObsLayout,
        sngnn: Option<SngnnSizes<'_>>,
    ) -> Self {
        let mut fields: Vec<(String, usize)> = vec![("n_envs".into(), n_envs)];
        for (columns, c, s) in [(state, "c_", "s_"), (outputs, "co_", "so_")] {
            let mut offset = [0usize; 2];
            for &(name, elem, stride) in columns {
                let k = usize::from(elem == Elem::U32);
                fields.push((format!("{c}{name}"), offset[k]));
                fields.push((format!("{s}{name}"), stride));
                offset[k] += n_envs * stride;
            }
        }
        for (kind, cap) in slot_kinds(state) {
            let (env_step, slot_step) = DEVICE_ORDER.steps(n_envs, cap);
            fields.push((format!("e_{kind}"), env_step));
            fields.push((format!("k_{kind}"), slot_step));
        }
        fields.push(("obs_dim".into(), obs.dim));
        fields.push(("obs_robot".into(), obs.robot));
        for (t, key) in crate::spec::ENTITY_KEYS.iter().enumerate() {
            fields.push((format!("obs_offset_{key}"), obs.offset[t]));
            fields.push((format!("obs_capacity_{key}"), obs.capacity[t]));
        }
        for (k, key) in crate::spec::INTERACTION_KEYS.iter().enumerate() {
            fields.push((format!("pairs_{}", key.replace('-', "_")), obs.pairs[k]));
        }
        let obstacles = ObstacleBuild::Now;
        fields.push(("pool_row".into(), pool_row_words(state, outputs, obstacles)));
        // Where a pool row's first observation starts: after the state's words.
        fields.push((
            "pool_observation".into(),
            pool_state_words(state, obstacles),
        ));
        // 1 when a pool row holds the ORCA obstacles ([`BatchLayout::with_pool_obstacles`]).
        fields.push(("pool_obstacles".into(), 1));
        let scratch = ObstacleScratch::of(state);
        let region = scratch_region_words(state);
        fields.push(("s_scratch".into(), region));
        fields.push(("obstacle_words".into(), scratch.words));
        fields.push(("x_obstacle_list".into(), scratch.list));
        fields.push(("x_obstacle_set".into(), scratch.set));
        fields.push(("x_obstacle_stack".into(), scratch.stack));
        for ((kind, _), (part, _)) in PERMUTED_KINDS.iter().zip(permute_parts(state)) {
            fields.push((format!("x_permute_{kind}"), part));
        }
        fields.push(("x_obs_staged".into(), n_envs * region));
        // 1 when the observation is staged ([`BatchLayout::with_staged_observation`]).
        fields.push(("obs_staged".into(), 0));
        // 1 when a dispatch of its own writes the entity records
        // ([`BatchLayout::with_records_apart`]).
        fields.push(("obs_records_apart".into(), 0));
        fields.extend(sngnn_sizes(sngnn));
        let fields = fields
            .into_iter()
            .map(|(name, v)| (name, u32::try_from(v).expect("a layout value fits a u32")))
            .collect();
        Self { fields }
    }

    /// This layout with the observation staged in `scratch` (`on`) or written into its rows in
    /// place: `obs_staged` (see [`scratch_words`], `GpuDevice::stage_observations`).
    pub fn with_staged_observation(self, on: bool) -> Self {
        self.with_flag("obs_staged", on)
    }

    /// This layout with the observation's entity records written by [`OBS_RECORDS_ENTRY`], a lane
    /// each, in a whole view (`on`), or by the observing lane: `obs_records_apart`
    /// (`GpuDevice::records_in_lanes`).
    pub fn with_records_apart(self, on: bool) -> Self {
        self.with_flag("obs_records_apart", on)
    }

    /// This layout with reset-pool rows whose ORCA obstacles are built as `obstacles` says:
    /// `pool_obstacles` 0, and `pool_row` and `pool_observation` without the words of
    /// [`POOL_OBSTACLE_COLUMNS`], where the rows leave them to the device
    /// (`GpuDevice::obstacles_after_resets`).
    #[expect(
        clippy::expect_used,
        reason = "the layout has a field per state column and for the pool"
    )]
    pub fn with_pool_obstacles(mut self, obstacles: ObstacleBuild) -> Self {
        if obstacles == ObstacleBuild::Now {
            return self;
        }
        let words: u32 = POOL_OBSTACLE_COLUMNS
            .iter()
            .map(|c| {
                self.get(&format!("s_{c}"))
                    .expect("a state column's stride")
            })
            .sum();
        for (name, v) in &mut self.fields {
            match name.as_str() {
                "pool_row" | "pool_observation" => *v -= words,
                "pool_obstacles" => *v = 0,
                _ => {}
            }
        }
        self
    }

    fn with_flag(mut self, field: &str, on: bool) -> Self {
        for (name, v) in &mut self.fields {
            if name == field {
                *v = u32::from(on);
            }
        }
        self
    }

    /// Value of field `name` (`c_episode`, `obs_dim`, ...), if there is one.
    pub fn get(&self, name: &str) -> Option<u32> {
        self.fields.iter().find(|(n, _)| n == name).map(|&(_, v)| v)
    }

    /// The uniform's contents: one word per field, in declaration order, padded to 16 bytes.
    pub fn words(&self) -> Vec<u32> {
        let mut words: Vec<u32> = self.fields.iter().map(|&(_, v)| v).collect();
        words.resize(words.len().next_multiple_of(4), 0);
        words
    }

    /// The WGSL declaration of the uniform's struct, `BatchLayout`.
    pub fn wgsl_struct(&self) -> String {
        let mut out = String::from("struct BatchLayout {\n");
        for (name, _) in &self.fields {
            out.push_str(&format!("    {name}: u32,\n"));
        }
        out.push_str("}\n");
        out
    }
}

/// One environment's region of the `scratch` buffer (binding 8 of [`prelude`]), the working
/// memory of ORCA's obstacle processing (`shaders/common/orca_obstacles.wgsl`), in words: a
/// polygon list (2 words and 8 a polygon, for a polygon per 8 obstacle vertices), a processed
/// vertex set (2 words and 7 columns of the vertex capacity) and the tree build's stack (3
/// columns of the vertex capacity). In [`BatchLayout`] as `x_obstacle_list`, `x_obstacle_set`,
/// `x_obstacle_stack` (where each part starts) and `obstacle_words` (its words); the region,
/// `s_scratch` words, also serves the slot permutations ([`scratch_region_words`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObstacleScratch {
    /// Words of the obstacle processing's working memory.
    pub words: usize,
    /// First word of the polygon list.
    pub list: usize,
    /// First word of the processed set.
    pub set: usize,
    /// First word of the stack.
    pub stack: usize,
}

/// Words of the `scratch` buffer of `n_envs` environments: every environment's
/// region ([`scratch_region_words`]), then, where the observation is staged (`staged_obs_dim`, its
/// floats, else 0), the observation as the observation pass writes it, slot-major from
/// `x_obs_staged` of the [`BatchLayout`]: value `i` of environment `e` at `x_obs_staged + i *
/// n_envs + e`, so that a warp's stores coalesce. The pass's second dispatch
/// ([`OBS_ROWS_ENTRY`]) moves it into the environment-major rows the host reads, through
/// workgroup memory.
pub fn scratch_words(n_envs: usize, state: Columns<'_>, staged_obs_dim: usize) -> usize {
    n_envs * (scratch_region_words(state) + staged_obs_dim)
}

/// Words of an environment's region of `scratch` (`s_scratch` of the [`BatchLayout`]): the
/// working memory of the obstacle rebuild ([`ObstacleScratch`]) and of the slot permutations
/// (the prelude's generated `state_permute_*`, every kind's part: `permute_words`), which
/// never run at once in one environment, so they share it. In every shipped config the
/// obstacles' part is the larger (exp2: 796 words against 162).
pub fn scratch_region_words(state: Columns<'_>) -> usize {
    ObstacleScratch::of(state).words.max(permute_words(state))
}

/// The entry point of `shaders/observation.wgsl` dispatched after its `main`: the staged
/// observation ([`scratch_words`]) into the rows of `obs`, one workgroup per [`WORKGROUP_SIZE`]
/// environments and [`OBS_ROWS_TILE`] floats.
pub const OBS_ROWS_ENTRY: &str = "rows";

/// The entry point of `shaders/observation.wgsl` dispatched after its `main` (and before
/// [`OBS_ROWS_ENTRY`]) on a batch whose entity records are written apart (`obs_records_apart` of
/// the [`BatchLayout`]), in a whole view: the entity records, one lane per environment and
/// record, a workgroup per [`WORKGROUP_SIZE`] environments and entity record of a row.
pub const OBS_RECORDS_ENTRY: &str = "records";

/// Floats of a row one workgroup of [`OBS_ROWS_ENTRY`] moves (the `OBS_TILE` of its shader): a
/// tile of `OBS_ROWS_TILE x (WORKGROUP_SIZE + 1)` words, 8,320 bytes of workgroup memory.
pub const OBS_ROWS_TILE: u32 = 32;
// `rows` hands each lane one value of every (WORKGROUP_SIZE / OBS_TILE)-th environment.
const _: () = assert!(WORKGROUP_SIZE.is_multiple_of(OBS_ROWS_TILE));

/// The stage whose shader has the [`OBS_ROWS_ENTRY`] entry point.
pub const OBS_ROWS_STAGE: &str = "observation";

impl ObstacleScratch {
    /// The region for a state table's obstacle vertex capacity (the stride of `ov_x`), with the
    /// shader's rounding (`orca_obstacles_cap`, `orca_obstacles_max_polygons`: at least 1 each).
    pub fn of(state: Columns<'_>) -> Self {
        let vertices = state
            .iter()
            .find(|c| c.0 == "ov_x")
            .map_or(0, |c| c.2)
            .max(1);
        Self::for_vertices(vertices)
    }

    /// The region for a capacity of `vertices` (at least 1): the list's 2 words and 8 a polygon,
    /// the set's 2 and 7 columns, the stack's 3 columns.
    pub const fn for_vertices(vertices: usize) -> Self {
        let polygons = if vertices / 8 > 1 { vertices / 8 } else { 1 };
        let list = 0;
        let set = list + 2 + 8 * polygons;
        let stack = set + 2 + 7 * vertices;
        Self {
            words: stack + 3 * vertices,
            list,
            set,
            stack,
        }
    }
}

/// The SNGNN-v2 fields of a [`BatchLayout`]: the history's capacities (`sn_frames`,
/// `sn_frame_people`, `sn_frame_objects`, `sn_frame_links`, `sn_entities`, `sn_walls`, each at
/// least 1) and the packed graph layout (`sn_max_nodes`, `sn_max_edges`, `sn_u32_stride`,
/// `sn_f32_stride`); all 0 without the graphs.
fn sngnn_sizes(sngnn: Option<SngnnSizes<'_>>) -> Vec<(String, usize)> {
    let names = [
        "sn_frames",
        "sn_frame_people",
        "sn_frame_objects",
        "sn_frame_links",
        "sn_entities",
        "sn_walls",
        "sn_max_nodes",
        "sn_max_edges",
        "sn_u32_stride",
        "sn_f32_stride",
    ];
    let values = match sngnn {
        None => [0; 10],
        Some(SngnnSizes { caps, graphs }) => {
            let at_least_one = |n: usize| n.max(1);
            [
                at_least_one(caps.frames),
                caps.frame_people,
                caps.frame_objects,
                caps.frame_links,
                at_least_one(caps.sngnn_entities),
                at_least_one(caps.walls),
                graphs.max_nodes,
                graphs.max_edges,
                graphs.u32_stride(),
                graphs.f32_stride(),
            ]
        }
    };
    names.into_iter().map(String::from).zip(values).collect()
}

/// The sizes of the shaders' function-scope arrays, the only config-dependent values compiled
/// into a shader: each the next power of two of a capacity, at least a floor that every shipped
/// config's capacities fit, so that they share compiled pipelines. The shaders compare counts
/// with the batch's own capacities (`batch.s_*`), never with these. (ORCA's obstacle processing,
/// whose arrays grow with the obstacle vertices, works in the `scratch` buffer instead: see
/// [`ObstacleScratch`].)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SizeClasses {
    /// `ARRAY_CROWD_MEMBERS`: members of one forming crowd (stride of `cf_human`).
    pub crowd_members: usize,
    /// `PERMUTE_CAP`: slots of the kinds the social events reorder (the largest stride).
    pub permute: usize,
    /// `ARRAY_SN_WALLS`: walls the SNGNN graph reads (stride of `w_x`).
    pub walls: usize,
}

/// The WGSL names of the [`SizeClasses`], in [`SizeClasses::values`] order.
pub const SIZE_CLASS_NAMES: [&str; 3] = ["ARRAY_CROWD_MEMBERS", "PERMUTE_CAP", "ARRAY_SN_WALLS"];

impl SizeClasses {
    /// The classes in [`SIZE_CLASS_NAMES`] order.
    pub fn values(&self) -> [usize; 3] {
        [self.crowd_members, self.permute, self.walls]
    }

    /// The classes of a state table's strides.
    pub fn of(state: Columns<'_>) -> Self {
        let stride = |col: &str| state.iter().find(|c| c.0 == col).map_or(0, |c| c.2);
        Self {
            crowd_members: size_class(stride("cf_human"), 8),
            permute: size_class(permuted_cap(state), 64),
            walls: size_class(stride("w_x"), 16),
        }
    }
}

/// The next power of two of `n`, at least `floor`.
fn size_class(n: usize, floor: usize) -> usize {
    n.max(floor).next_power_of_two()
}

/// The part of every shader's head that depends on neither the config nor the batch: the constants
/// [`prelude`] lists before the size classes (`WORKGROUP_SIZE`, `INFO_*`, `EP_*`, `EV_*`, the
/// shared codes and f32 constants, `OBS_RECORD`, `OBS_ONE_HOT`, `OBS_TILE`,
/// [`geometry_constants`]). A kernel built from the shader library outside the step
/// (tests/suite/orca/gpu.rs) starts with it, so the library's files see the same definitions there
/// as in the step.
pub fn shared_head() -> String {
    let mut out = format!("const WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;\n");
    for (keys, prefix) in [
        (&crate::spec::INFO_KEYS[..], "INFO_"),
        (&crate::spec::EPISODE_KEYS[..], "EP_"),
        (&crate::spec::EVENT_KEYS[..], "EV_"),
    ] {
        for (k, key) in keys.iter().enumerate() {
            out.push_str(&format!(
                "const {prefix}{}: u32 = {k}u;\n",
                key.to_uppercase()
            ));
        }
    }
    for (name, value) in shared_constants() {
        out.push_str(&format!("const {name}: u32 = {value}u;\n"));
    }
    for (name, value) in shared_f32_constants() {
        out.push_str(&format!("const {name}: f32 = {};\n", wgsl_f32(value)));
    }
    out.push_str(&format!(
        "const OBS_RECORD: u32 = {}u;\nconst OBS_ONE_HOT: u32 = {}u;\n",
        crate::spec::RECORD,
        crate::spec::ONE_HOT
    ));
    out.push_str(&format!("const OBS_TILE: u32 = {OBS_ROWS_TILE}u;\n"));
    out.push_str(ORCA_LISTS_KEPT);
    out.push_str(RESETS_BY_ONE_LANE);
    out.push_str(REGROUPS_BY_ONE_LANE);
    out.push_str(&geometry_constants());
    out
}

/// The line of [`shared_head`] that leaves the ORCA lists' entries as they were at a clear
/// (`shaders/common/orca.wgsl`); [`with_poisoned_orca_lists`] turns it.
const ORCA_LISTS_KEPT: &str = "const ORCA_POISON_LISTS: bool = false;\n";

/// `src` (a prelude, or a shader assembled from one) with the ORCA lists poisoned at every clear:
/// every entry NaN, every index one no list holds (`GpuDevice::poison_orca_lists`, for the test
/// that no entry is read before it is written).
pub fn with_poisoned_orca_lists(src: &str) -> String {
    src.replacen(
        ORCA_LISTS_KEPT,
        "const ORCA_POISON_LISTS: bool = true;\n",
        1,
    )
}

/// The line of [`shared_head`] that gives each reset of a step one lane
/// (`shaders/common/pool_reset.wgsl`); [`with_resets_in_workgroups`] turns it.
const RESETS_BY_ONE_LANE: &str = "const RESET_LANES: u32 = 1u;\n";

/// The line of [`shared_head`] that gives each regrouping of a step's social events and
/// formations one lane (`shaders/common/regroup.wgsl`); [`with_regroups_in_workgroups`] turns it.
const REGROUPS_BY_ONE_LANE: &str = "const REGROUP_LANES: u32 = 1u;\n";

/// Bytes of workgroup memory a regrouping on a workgroup's lanes takes with these size classes
/// (`shaders/common/regroup.wgsl`'s `regroup_wg_*`: the four kinds' sort keys (four words each),
/// sorted slots and inverses, each group's members and first member, a few words): with
/// `PERMUTE_CAP` 64, 6.6 KiB.
pub fn regroup_workgroup_bytes(classes: &SizeClasses) -> usize {
    4 * (26 * classes.permute + 4 + 4 + 4 + 2 + 1)
}

/// `src` (a prelude, or a shader assembled from one) with each environment that `formation` and
/// `social_events` work on taken by all the lanes of a workgroup, its regroupings shared out
/// among them (`GpuDevice::regroups_in_workgroups`, where [`regroup_workgroup_bytes`] fits the
/// device).
pub fn with_regroups_in_workgroups(src: &str) -> String {
    src.replacen(
        REGROUPS_BY_ONE_LANE,
        "const REGROUP_LANES: u32 = WORKGROUP_SIZE;\n",
        1,
    )
}

/// `src` (a prelude, or a shader assembled from one) with each reset of a step run by all the
/// lanes of a workgroup (`GpuDevice::resets_in_workgroups`).
pub fn with_resets_in_workgroups(src: &str) -> String {
    src.replacen(
        RESETS_BY_ONE_LANE,
        "const RESET_LANES: u32 = WORKGROUP_SIZE;\n",
        1,
    )
}

/// `src` (a shader) with each function of `names` that it defines returning at once: nothing, or
/// its return type's zero value (`T()`). For diagnosis only (`GpuDevice::leave_out`): a pass
/// timed without one of its functions says what that function costs on a device, and its results
/// are wrong. Also returns the names found (a function is defined at the start of a line: `fn
/// name(`).
pub fn with_functions_returning_at_once<'a>(
    src: &str,
    names: &'a [String],
) -> (String, Vec<&'a str>) {
    let mut out = src.to_owned();
    let mut found = Vec::new();
    for name in names {
        let head = format!("\nfn {name}(");
        let Some(at) = out.find(&head) else {
            continue;
        };
        // The body's brace is the first after the head: a signature holds none.
        let Some(brace) = out[at..].find('{').map(|k| at + k) else {
            continue;
        };
        let returned = match out[at..brace].split_once("->") {
            Some((_, ty)) => format!("return {}();", ty.trim()),
            None => "return;".to_owned(),
        };
        out.insert_str(
            brace + 1,
            &format!("\n    {returned} // left out (diagnosis)"),
        );
        found.push(name.as_str());
    }
    (out, found)
}

/// The generated head of every shader: [`shared_head`] (the constants shared with the Rust stages:
/// `WORKGROUP_SIZE`, `INFO_*`/`EP_*`/`EV_*`, `NONE`, `ROLE_*`, `STREAM_*`, `POLICY_*`, `ONE_HOT_*`,
/// `REWARD_SNGNN`, `SNGNN_WEIGHT`, `CONTACT_*`, `ORCA_RVO_EPSILON`, ...), the array sizes of
/// [`SizeClasses`], the struct `StepParams` ([`step_params_struct`], the storage buffer `params`),
/// the struct of [`BatchLayout`] (the uniform `batch`), the bindings every shader shares, the
/// element index of each slot kind (`at_<kind>`, `slot_<kind>`: the only place that knows the
/// [`DEVICE_ORDER`]), the slot permutations of the social events (`state_permute_*`, generated by
/// `permute_functions`), the queues of the rare work (`schedule::has_rare_work`) and the reset
/// pool's copies (`pool_copy_*`). Only `classes` depends on the config; nothing on the batch size.
pub fn prelude(state: Columns<'_>, outputs: Columns<'_>, classes: &SizeClasses) -> String {
    let mut out = String::from("// Generated by src/backend/wgsl.rs.\n");
    out.push_str(&shared_head());
    for (name, value) in SIZE_CLASS_NAMES.into_iter().zip(classes.values()) {
        out.push_str(&format!("const {name}: u32 = {value}u;\n"));
    }
    out.push_str(&step_params_struct());
    let layout = BatchLayout::new(0, state, outputs, &crate::spec::ObsLayout::default(), None);
    out.push_str(&layout.wgsl_struct());
    out.push_str(
        "@group(0) @binding(0) var<storage, read> params: StepParams;\n\
         @group(0) @binding(1) var<storage, read_write> sf: array<f32>;\n\
         @group(0) @binding(2) var<storage, read_write> su: array<u32>;\n\
         @group(0) @binding(3) var<storage, read> actions: array<f32>;\n\
         @group(0) @binding(4) var<storage, read_write> outf: array<f32>;\n\
         @group(0) @binding(5) var<storage, read_write> outu: array<u32>;\n\
         @group(0) @binding(6) var<storage, read> pool: array<u32>;\n\
         @group(0) @binding(7) var<uniform> batch: BatchLayout;\n\
         @group(0) @binding(8) var<storage, read_write> scratch: array<u32>;\n\
         @group(0) @binding(10) var<uniform> pass_members: vec4<u32>;\n",
    );
    out.push_str(&slot_index_functions(state));
    out.push_str(&rare_work_functions());
    out.push_str(&permute_functions(state));
    out.push_str(&pool_functions(state, outputs));
    out
}

/// The SNGNN part of a prelude, appended to [`prelude`] for the shaders that build SNGNN-v2's
/// graphs ([`needs_sngnn`]): the code's
/// constants (`SN_MAX_GRAPH_FRAMES`, the packed graph words `SN_WORD_*`, the node feature
/// indices `SN_F_*`, `SN_NODE_FEATURES` and relations `SN_REL_*`, the frame's command scales and
/// period and the graph's scales and thresholds as f32, from their Rust definitions in
/// [`crate::sngnn`])
/// and the bindings of group 1: the packed graphs, 0 (`sn_gu`, u32 region) and 1 (`sn_gf`, f32),
/// and the frame selection's gaps, 2 (`sn_gaps`, [`crate::sngnn::history::TickGaps::words`]). The
/// sizes are the `sn_*` fields of [`BatchLayout`]. Only the shaders that use them get them, so
/// that every other shader's pipeline is the same with and without the SNGNN-v2 reward.
pub fn sngnn_prelude() -> String {
    use crate::sngnn::{NODE_FEATURES, feature as f, frame, graph, history, packed::words, rel};
    let values: Vec<(&str, usize)> = vec![
        ("SN_WORD_NODES", words::NODES),
        ("SN_WORD_EDGES", words::EDGES),
        ("SN_WORD_SRC", words::SRC),
        ("SN_MAX_GRAPH_FRAMES", history::MAX_GRAPH_FRAMES),
        ("SN_NODE_FEATURES", NODE_FEATURES),
        ("SN_F_HUMAN", f::HUMAN),
        ("SN_F_OBJECT", f::OBJECT),
        ("SN_F_ROOM", f::ROOM),
        ("SN_F_WALL", f::WALL),
        ("SN_F_GOAL", f::GOAL),
        ("SN_F_IS_T", f::IS_T),
        ("SN_F_PERSON", f::PERSON),
        ("SN_F_ROBOT", f::ROBOT),
        ("SN_F_OBJECT_BASE", f::OBJECT_BASE),
        ("SN_F_ROOM_HUMANS", f::ROOM_HUMANS),
        ("SN_F_WALL_BASE", f::WALL_BASE),
        ("SN_F_GOAL_BASE", f::GOAL_BASE),
    ];
    let relations = [
        ("G_R", rel::G_R),
        ("O_P", rel::O_P),
        ("O_R", rel::O_R),
        ("P_O", rel::P_O),
        ("P_P", rel::P_P),
        ("P_R", rel::P_R),
        ("P_W", rel::P_W),
        ("R_G", rel::R_G),
        ("R_O", rel::R_O),
        ("R_P", rel::R_P),
        ("R_W", rel::R_W),
        ("SELF", rel::SELF),
        ("W_P", rel::W_P),
        ("W_R", rel::W_R),
        ("TEMPORAL", rel::TEMPORAL),
    ];
    let mut out = String::from("// SNGNN-v2 graph building (backend::wgsl::sngnn_prelude).\n");
    for (name, v) in values {
        out.push_str(&format!("const {name}: u32 = {v}u;\n"));
    }
    for (name, v) in relations {
        out.push_str(&format!("const SN_REL_{name}: u32 = {v}u;\n"));
    }
    let floats = [
        ("SN_ADVANCE_SCALE", frame::ADVANCE_SCALE),
        ("SN_MAX_ADVANCE", frame::MAX_ADVANCE),
        ("SN_ROTATION_SCALE", frame::ROTATION_SCALE),
        ("SN_MAX_ROTATION", frame::MAX_ROTATION),
        ("SN_FRAME_PERIOD", frame::FRAME_PERIOD),
        ("SN_POSITION_SCALE", graph::POSITION_SCALE),
        ("SN_MAX_HUMANS", graph::MAX_HUMANS),
        // graph.rs divides by `MAX_HUMANS * MAX_HUMANS`, which Rust folds to this f32.
        ("SN_MAX_HUMANS_SQ", graph::MAX_HUMANS * graph::MAX_HUMANS),
        ("SN_SEGMENT_CM", graph::WALL_SEGMENT_CM),
        ("SN_HUMAN_WALL_THRESHOLD", graph::HUMAN_WALL_THRESHOLD),
    ];
    for (name, v) in floats {
        out.push_str(&format!("const {name}: f32 = {};\n", wgsl_f32(v)));
    }
    out.push_str(
        "@group(1) @binding(0) var<storage, read_write> sn_gu: array<u32>;\n\
         @group(1) @binding(1) var<storage, read_write> sn_gf: array<f32>;\n\
         @group(1) @binding(2) var<storage, read> sn_gaps: array<u32>;\n",
    );
    out
}

/// The output columns a reset writes from the pool (the first observation of an episode); the
/// rest of what a reset writes (reward, flags, info) are constants.
pub const POOL_OUTPUT_COLUMNS: [&str; 5] =
    ["obs", "obs_count", "hh_pairs", "hl_pairs", "pair_count"];

/// The state columns of an environment's processed ORCA obstacles, which a reset-pool row that
/// leaves them to the device ([`ObstacleBuild::Deferred`]) does not hold: two fifths of an exp2
/// row, which the host would write, the device's pool keep and every reset copy, only for the
/// rebuild to replace. Such a row's copy leaves the environment's old obstacles in place, their
/// count included, and the rebuild after it ([`rebuilds_resets`]: the submit's one rebuild
/// of the [`REBUILD_QUEUE`], or the reset pass's own) replaces them, zeroing the old tail past
/// the new count as every rebuild does: the bits of a build on the host.
pub const POOL_OBSTACLE_COLUMNS: [&str; 8] = [
    "ov_x",
    "ov_y",
    "ov_dir_x",
    "ov_dir_y",
    "ov_next",
    "ov_prev",
    "ov_convex",
    "n_obstacle_vertices",
];

/// Whether a reset-pool row whose obstacles are built as `obstacles` says holds state column
/// `name` ([`POOL_OBSTACLE_COLUMNS`]).
pub fn pool_holds(name: &str, obstacles: ObstacleBuild) -> bool {
    obstacles == ObstacleBuild::Now || !POOL_OBSTACLE_COLUMNS.contains(&name)
}

/// 32-bit words of one environment's state in a reset-pool row ([`pool_row_words`]).
fn pool_state_words(state: Columns<'_>, obstacles: ObstacleBuild) -> usize {
    state
        .iter()
        .filter(|c| pool_holds(c.0, obstacles))
        .map(|c| c.2)
        .sum()
}

/// 32-bit words of one environment's row in the reset pool: every state column it holds
/// ([`pool_holds`]: all but the obstacles' where the row leaves them to the device), f32 columns
/// first then u32 columns, each in declaration order, then the [`POOL_OUTPUT_COLUMNS`] in that
/// order. A one-environment table packed by `soa!`'s `pack_words`, less the columns the row
/// does not hold, is exactly the state part (`backend::reset_pool`).
pub fn pool_row_words(state: Columns<'_>, outputs: Columns<'_>, obstacles: ObstacleBuild) -> usize {
    pool_state_words(state, obstacles) + pool_outputs(outputs).map(|c| c.2).sum::<usize>()
}

#[expect(
    clippy::expect_used,
    reason = "POOL_OUTPUT_COLUMNS names output columns (unit-tested)"
)]
fn pool_outputs<'a>(
    outputs: Columns<'a>,
) -> impl Iterator<Item = &'a (&'static str, Elem, usize)> + Clone {
    POOL_OUTPUT_COLUMNS.iter().map(move |name| {
        outputs
            .iter()
            .find(|c| c.0 == *name)
            .expect("the pool's output columns exist")
    })
}

/// The generated copies of a pool row (`batch.pool_row` words from `row * batch.pool_row`) into
/// environment `e`'s state (`pool_copy_state`) and first-observation outputs
/// (`pool_copy_observation`), one loop per column (layout: [`pool_row_words`]), and the row an
/// environment's next reset copies (`pool_row_of`, and back: `pool_env_of`): the pool holds two
/// rows per environment, the next episode's and the one after it, in two halves of
/// `batch.n_envs` rows chosen by the parity of the episode counter the row starts, so that the
/// host can write the second while the device consumes the first (`GpuBackend`'s refill).
///
/// Each copy takes the slots `first, first + stride, ...` of every column: one lane copies a
/// whole row with `(0, 1)`, and a workgroup's lanes share one with `(lane, WORKGROUP_SIZE)`, each
/// lane then writing the same slots of every column, so the lanes of a reset never touch one
/// word twice (`shaders/common/pool_reset.wgsl`).
fn pool_functions(state: Columns<'_>, outputs: Columns<'_>) -> String {
    let copy = |name: &str, elem: Elem, prefix: (&str, &str), out: &mut String| {
        let (c, s) = prefix;
        let (buf, value) = match (elem, c) {
            (Elem::F32, "c_") => ("sf", "bitcast<f32>(pool[w + j])"),
            (Elem::U32, "c_") => ("su", "pool[w + j]"),
            (Elem::F32, _) => ("outf", "bitcast<f32>(pool[w + j])"),
            (Elem::U32, _) => ("outu", "pool[w + j]"),
        };
        // A pool row is one environment's, so in every order its slots are consecutive words.
        let at = match kind_of(name).filter(|&k| c == "c_" && k != "env") {
            Some(kind) => format!("at_{kind}(e, j)"),
            None => format!("e * batch.{s}{name} + j"),
        };
        let copy = format!(
            "for (var j = first; j < batch.{s}{name}; j += stride) {{ {buf}[batch.{c}{name} + {at}] = {value}; }}\n\
             \x20   w += batch.{s}{name};"
        );
        if c == "c_" && POOL_OBSTACLE_COLUMNS.contains(&name) {
            out.push_str(&format!(
                "    if (batch.pool_obstacles != 0u) {{\n    {copy}\n    }}\n"
            ));
        } else {
            out.push_str(&format!("    {copy}\n"));
        }
    };
    let mut out = String::from(
        "fn pool_row_of(e: u32) -> u32 {\n    return ((su[batch.c_episode + e] + 1u) & 1u) * batch.n_envs + e;\n}\n\
         fn pool_env_of(row: u32) -> u32 {\n    return row % batch.n_envs;\n}\n\
         fn pool_copy_state(e: u32, row: u32, first: u32, stride: u32) {\n    var w = row * batch.pool_row;\n",
    );
    for elem in [Elem::F32, Elem::U32] {
        for &(name, el, _) in state.iter().filter(|c| c.1 == elem) {
            copy(name, el, ("c_", "s_"), &mut out);
        }
    }
    out.push_str(
        "}\nfn pool_copy_observation(e: u32, row: u32, first: u32, stride: u32) {\n    var w = row * batch.pool_row + batch.pool_observation;\n",
    );
    for &(name, el, _) in pool_outputs(outputs) {
        copy(name, el, ("co_", "so_"), &mut out);
    }
    out.push_str("}\n");
    out
}

/// The output columns of a finished environment's row in the step readback
/// ([`finished_rows_shader`]): [`crate::outputs::FINISHED_ONLY_COLUMNS`], f32 columns first then
/// u32 columns, each in declaration order (the order of the row after its environment index).
pub fn finished_columns<'a>(outputs: Columns<'a>) -> Vec<&'a (&'static str, Elem, usize)> {
    let finished = |c: &&(&str, Elem, usize)| crate::outputs::FINISHED_ONLY_COLUMNS.contains(&c.0);
    let of = |elem| outputs.iter().filter(finished).filter(move |c| c.1 == elem);
    of(Elem::F32).chain(of(Elem::U32)).collect()
}

/// 32-bit words of a finished environment's row in the step readback: its index, then its words
/// of [`finished_columns`].
pub fn finished_row_words(outputs: Columns<'_>) -> usize {
    1 + finished_columns(outputs).iter().map(|c| c.2).sum::<usize>()
}

/// The finished-rows pass of the GPU backend's step readback (`backend::gpu::readback`), a
/// standalone shader generated from the output columns: every environment whose episode ended
/// at this step (`has_final` or `episode_done`) appends its row ([`finished_row_words`]) to
/// `finished.words` at a slot taken with an atomic counter, `finished.count`, so that the host
/// reads the [`crate::outputs::FINISHED_ONLY_COLUMNS`] of those environments alone. The slots'
/// order varies from run to run; each row carries its environment, and the host writes it there.
/// Bindings: the output tables (`outf`, `outu`, read-only), the batch layout (the uniform
/// `batch`, as in [`prelude`]) and `finished`.
pub fn finished_rows_shader(state: Columns<'_>, outputs: Columns<'_>) -> String {
    let layout = BatchLayout::new(0, state, outputs, &crate::spec::ObsLayout::default(), None);
    let columns = finished_columns(outputs);
    let row: String = columns
        .iter()
        .map(|c| format!(" + batch.so_{}", c.0))
        .collect();
    let mut out = String::from("// Generated by src/backend/wgsl.rs (finished_rows_shader).\n");
    out.push_str(&format!("const WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;\n"));
    out.push_str(&layout.wgsl_struct());
    out.push_str(
        "struct Finished {\n    count: atomic<u32>,\n    words: array<u32>,\n}\n\
         @group(0) @binding(0) var<storage, read> outf: array<f32>;\n\
         @group(0) @binding(1) var<storage, read> outu: array<u32>;\n\
         @group(0) @binding(2) var<uniform> batch: BatchLayout;\n\
         @group(0) @binding(3) var<storage, read_write> finished: Finished;\n\
         @compute @workgroup_size(WORKGROUP_SIZE)\n\
         fn main(@builtin(global_invocation_id) gid: vec3<u32>) {\n\
         \x20   let e = gid.x;\n\
         \x20   if (e >= batch.n_envs || (outu[batch.co_has_final + e] == 0u && outu[batch.co_episode_done + e] == 0u)) {\n\
         \x20       return;\n\
         \x20   }\n",
    );
    out.push_str(&format!(
        "    var w = atomicAdd(&finished.count, 1u) * (1u{row});\n    finished.words[w] = e;\n    w += 1u;\n"
    ));
    for &&(name, elem, _) in &columns {
        let value = match elem {
            Elem::F32 => "bitcast<u32>(outf[c + j])",
            Elem::U32 => "outu[c + j]",
        };
        out.push_str(&format!(
            "    {{\n        let c = batch.co_{name} + e * batch.so_{name};\n        \
             for (var j = 0u; j < batch.so_{name}; j++) {{ finished.words[w + j] = {value}; }}\n        \
             w += batch.so_{name};\n    }}\n"
        ));
    }
    out.push_str("}\n");
    out
}

/// The queues of the stages with rare work and the [`REBUILD_QUEUE`]: their indices `RARE_<STAGE>`
/// and `RARE_REBUILD`, the binding `rare` (9), and `rare_push` (queue an environment) and
/// `rare_env` (lane `k`'s environment, or `NONE` past the queue's end).
fn rare_work_functions() -> String {
    let mut out = String::new();
    // The queues in `pipeline::rare_queue`'s order: the stages with rare work, in step order.
    let rare = crate::pipeline::STAGES.iter().filter(|s| s.gpu.rare_work);
    for (k, stage) in rare.enumerate() {
        out.push_str(&format!(
            "const RARE_{}: u32 = {k}u;\n",
            stage.name.to_uppercase()
        ));
    }
    out.push_str(&format!("const RARE_REBUILD: u32 = {REBUILD_QUEUE}u;\n"));
    out.push_str(&format!(
        "struct RareWork {{\n    count: array<atomic<u32>, {n}>,\n    list: array<u32>,\n}}\n\
         @group(0) @binding(9) var<storage, read_write> rare: RareWork;\n\
         fn rare_push(queue: u32, e: u32) {{\n\
         \x20   rare.list[queue * batch.n_envs + atomicAdd(&rare.count[queue], 1u)] = e;\n}}\n\
         fn rare_env(queue: u32, k: u32) -> u32 {{\n\
         \x20   if (k >= atomicLoad(&rare.count[queue])) {{\n        return NONE;\n    }}\n\
         \x20   return rare.list[queue * batch.n_envs + k];\n}}\n",
        n = RARE_QUEUES
    ));
    out
}

/// The slot kinds whose slots the social events reorder, with the WGSL name of their permutation.
const PERMUTED_KINDS: [(&str, &str); 4] = [
    ("human", "state_permute_humans"),
    ("group", "state_permute_groups"),
    ("laptop_user", "state_permute_laptop_users"),
    ("laptop", "state_permute_laptops"),
];

/// The kind of state column `col` (`human`, `group`, ...), from `soa!`'s declaration.
fn kind_of(col: &str) -> Option<&'static str> {
    crate::state::BatchState::COLUMN_KINDS
        .iter()
        .find(|&&(c, _)| c == col)
        .map(|&(_, k)| k)
}

/// The largest capacity of the kinds the social events reorder (0 if none).
fn permuted_cap(state: Columns<'_>) -> usize {
    PERMUTED_KINDS
        .iter()
        .flat_map(|&(kind, _)| columns_of(state, kind))
        .map(|&(_, _, stride)| stride)
        .max()
        .unwrap_or(0)
}

/// The state columns of slot kind `kind`, in declaration order.
fn columns_of<'a>(state: Columns<'a>, kind: &str) -> Vec<&'a (&'static str, Elem, usize)> {
    state
        .iter()
        .filter(|c| kind_of(c.0) == Some(kind))
        .collect()
}

/// Words of the `scratch` region the slot permutations of environment `e` pass their old slots
/// through ([`permute_functions`]): a part for each kind, a word per column and slot, so that a
/// regrouping on a workgroup's lanes moves every kind's slots at once.
fn permute_words(state: Columns<'_>) -> usize {
    permute_parts(state)
        .last()
        .map_or(0, |&(at, words)| at + words)
}

/// Where each kind of [`PERMUTED_KINDS`] keeps its old slots in an environment's region of
/// `scratch`, and how many words they take: (offset, words), the kinds end to end.
fn permute_parts(state: Columns<'_>) -> Vec<(usize, usize)> {
    let mut at = 0;
    PERMUTED_KINDS
        .iter()
        .map(|&(kind, _)| {
            let columns = columns_of(state, kind);
            let words = columns.len() * columns.iter().map(|c| c.2).max().unwrap_or(0);
            at += words;
            (at - words, words)
        })
        .collect()
}

/// The twins of `StateChunk::permute` for the kinds the social events reorder, generated from the
/// state's column list (so a column added to a kind is permuted without touching a shader): per
/// kind `fn state_permute_<kinds>(e: u32, perm: array<u32, PERMUTE_CAP>, n: u32, used: u32)`,
/// which reorders the first `used` slots of that kind of environment `e` in every column of the
/// kind: slot `k` receives the old slot `perm[k]` for `k < n`, and slots `n..used` are zeroed.
/// (`PERMUTE_CAP`, the array size, is a [`SizeClasses`] class at least the largest capacity of
/// those kinds.) It runs in two halves, each a slot at a time, which a regrouping on a
/// workgroup's lanes calls a slot a lane with a barrier between (`regroup_canonicalize_on_lanes`):
/// `fn state_permute_<kinds>_save(e: u32, k: u32, old: u32)`, old slot `old` into place `k` of
/// the kind's part of the region, and `fn state_permute_<kinds>_restore(e: u32, k: u32, kept:
/// bool)`, slot `k` from place `k` (or zeroed where not `kept`). Each kind has a part of its own
/// ([`permute_parts`]; `x_permute_<kind>` of the [`BatchLayout`], data, so that the prelude stays
/// the same for every config), so the lanes move every kind's slots between the same two
/// barriers.
///
/// The old slots pass through the environment's region of `scratch` ([`scratch_region_words`];
/// the obstacle rebuild's working memory, free here: the rebuild runs in a dispatch of its own
/// after the regrouping, and nothing in the region outlives a call), a slot's every column at
/// once: the loads of one slot's columns are independent of each other and of the stores into
/// another buffer, so a GPU has them all in flight at once, where a column at a time through a
/// function-scope array waited a memory round trip for every column and slot (the regrouping's
/// permutations took 0.3-0.5 ms of exp2's step on an H100, one lane's chain). It moves bits, so
/// the slots are those the CPU's permutation gives.
fn permute_functions(state: Columns<'_>) -> String {
    let mut out =
        String::from("fn scratch_region(e: u32) -> u32 {\n    return e * batch.s_scratch;\n}\n");
    for (kind, name) in PERMUTED_KINDS {
        let columns = columns_of(state, kind);
        let width = columns.len();
        out.push_str(&format!(
            "fn {name}(e: u32, perm: array<u32, PERMUTE_CAP>, n: u32, used: u32) {{\n\
             \x20   for (var k = 0u; k < n; k++) {{\n\
             \x20       {name}_save(e, k, perm[k]);\n    }}\n\
             \x20   for (var k = 0u; k < used; k++) {{\n\
             \x20       {name}_restore(e, k, k < n);\n    }}\n}}\n\
             fn {name}_save(e: u32, k: u32, old_slot: u32) {{\n\
             \x20   let old = at_{kind}(e, old_slot);\n\
             \x20   let to = scratch_region(e) + batch.x_permute_{kind} + k * {width}u;\n"
        ));
        for (j, &&(col, elem, _)) in columns.iter().enumerate() {
            let value = match elem {
                Elem::F32 => format!("bitcast<u32>(sf[batch.c_{col} + old])"),
                Elem::U32 => format!("su[batch.c_{col} + old]"),
            };
            out.push_str(&format!("    scratch[to + {j}u] = {value};\n"));
        }
        out.push_str(&format!(
            "}}\n\
             fn {name}_restore(e: u32, k: u32, kept: bool) {{\n\
             \x20   let at = at_{kind}(e, k);\n\
             \x20   if (kept) {{\n\
             \x20       let kept_at = scratch_region(e) + batch.x_permute_{kind} + k * {width}u;\n"
        ));
        let mut zeroes = String::new();
        for (j, &&(col, elem, _)) in columns.iter().enumerate() {
            let (buf, value, zero) = match elem {
                Elem::F32 => (
                    "sf",
                    format!("bitcast<f32>(scratch[kept_at + {j}u])"),
                    "0.0",
                ),
                Elem::U32 => ("su", format!("scratch[kept_at + {j}u]"), "0u"),
            };
            out.push_str(&format!("        {buf}[batch.c_{col} + at] = {value};\n"));
            zeroes.push_str(&format!("        {buf}[batch.c_{col} + at] = {zero};\n"));
        }
        out.push_str(&format!("    }} else {{\n{zeroes}    }}\n}}\n"));
    }
    out
}

/// The codes the shaders share with the Rust stages, by their WGSL names: the absent index, human
/// roles, group kinds, the ORCA policy, a walker's forming-crowd mark, the rejection samplers'
/// try limit, RNG stream kinds, the robot's noise slot, the observation's one-hot positions and
/// the SNGNN-v2 reward's kind and the obstacle flag of a rebuild that overflowed.
#[expect(clippy::expect_used, reason = "the constants are small table indices")]
fn shared_constants() -> Vec<(&'static str, u32)> {
    use crate::params::AutoresetMode;
    use crate::spec::one_hot;
    use crate::state::{forming, group_kind, policy, role};
    use crate::systems;
    let index = |i: usize| u32::try_from(i).expect("a small index");
    vec![
        ("NONE", crate::state::NONE),
        ("AUTORESET_SAME_STEP", AutoresetMode::SameStep.code()),
        ("AUTORESET_NEXT_STEP", AutoresetMode::NextStep.code()),
        ("ROLE_STATIC", role::STATIC),
        ("ROLE_DYNAMIC", role::DYNAMIC),
        ("ROLE_MOVING_GROUP", role::MOVING_GROUP),
        ("ROLE_STANDING_GROUP", role::STANDING_GROUP),
        ("ROLE_LAPTOP_USER", role::LAPTOP_USER),
        ("GROUP_MOVING", group_kind::MOVING),
        ("GROUP_STANDING", group_kind::STANDING),
        ("GROUP_DISSOLVED", group_kind::DISSOLVED),
        ("STREAM_SCENARIO", crate::scenario::STREAM_SCENARIO),
        ("STREAM_GOALS", systems::goals::STREAM_GOALS),
        (
            "STREAM_AVOID_ROBOT",
            systems::human_motion::STREAM_AVOID_ROBOT,
        ),
        (
            "STREAM_GROUP_NOISE",
            systems::group_motion::STREAM_GROUP_NOISE,
        ),
        ("STREAM_FORMATION", systems::formation::STREAM_FORMATION),
        ("STREAM_SOCIAL", systems::social_events::STREAM_SOCIAL),
        ("STREAM_OBS_NOISE", systems::observation::STREAM_OBS_NOISE),
        ("FORMING_NONE", forming::NONE),
        ("FORMING_CROWD", forming::CROWD),
        ("FORMING_LAPTOP", forming::LAPTOP),
        ("POLICY_ORCA", policy::ORCA),
        ("POLICY_SFM", policy::SFM),
        ("COUNT_GROUP_SIZE", index(crate::params::count::GROUP_SIZE)),
        ("PLACE_MAX_TRIES", crate::scenario::place::MAX_TRIES),
        ("PLACE_MAX_GROUP", index(crate::scenario::place::MAX_GROUP)),
        (
            "FORMATION_APPROXIMATE_AFTER",
            systems::formation::APPROXIMATE_AFTER,
        ),
        ("NOISE_ROBOT", index(crate::params::NOISE_ROBOT)),
        // The entity records' one-hot floats are the host's (`backend::obs_payload`).
        ("ONE_HOT_ROBOT", index(one_hot::ROBOT)),
        ("REWARD_SNGNN", systems::reward::REWARD_SNGNN),
        (
            "ORCA_OBSTACLES_FAILED",
            systems::orca_obstacles::OBSTACLES_FAILED,
        ),
    ]
}

/// The f32 constants the shaders share with the Rust stages, by their WGSL names, written into
/// the prelude as exact hexadecimal literals ([`wgsl_f32`]): the SNGNN-v2 reward's weight, the
/// contact force's margin, stiffness and slop, the personal-space threshold of the metrics,
/// perception's full-view tolerance and `f32::MAX` (a ray's far end), the social force weight,
/// RVO2's epsilon and the obstacle prefilter's margin factor.
fn shared_f32_constants() -> Vec<(&'static str, f32)> {
    use crate::systems;
    vec![
        ("SNGNN_WEIGHT", systems::reward::SNGNN_WEIGHT),
        ("CONTACT_MARGIN", systems::contacts::MARGIN),
        ("CONTACT_STIFFNESS", systems::contacts::STIFFNESS),
        ("CONTACT_SLOP", systems::contacts::CONTACT_SLOP),
        ("PERSONAL_SPACE", systems::metrics::PERSONAL_SPACE),
        (
            "PERCEPTION_FULL_VIEW_TOLERANCE",
            systems::perception::FULL_VIEW_TOLERANCE,
        ),
        ("PERCEPTION_F32_MAX", f32::MAX),
        ("SFM_W", systems::sfm::W),
        ("ORCA_RVO_EPSILON", crate::orca::RVO_EPSILON),
        (
            "ORCA_OBSTACLE_REJECT_FACTOR",
            crate::orca::OBSTACLE_REJECT_FACTOR,
        ),
    ]
}

/// The complete source of `shaders/<path>` for a batch: the prelude, then the file's
/// requirements and the file. (Module-scope WGSL declarations may come in any order; the files
/// follow their dependencies for the reader.) Stage `s` is `s.wgsl`.
///
/// A size class's constant is left out of a shader that does not use it, so that configs
/// differing in that class alone share the shader.
pub fn assemble(path: &str, prelude: &str) -> Result<String, String> {
    let body = concatenate(String::new(), &resolve(path)?);
    Ok(format!("{}{body}", used_size_classes_only(prelude, &body)))
}

/// The complete source of pass `pass` (`schedule::passes`) for a batch: for a fused pass
/// (`schedule::fused_passes`), the prelude, every member's requirements and file (each file once),
/// then the generated entry point; for any other, [`assemble`] of `<pass>.wgsl`, with the generated
/// rebuild entry points of a pass that [`regroups`] ([`REBUILD_ENTRY`],
/// [`REBUILD_IN_WORKGROUPS_ENTRY`]).
pub fn assemble_pass(pass: &str, prelude: &str) -> Result<String, String> {
    let Some(fused) = FusedPass::named(pass) else {
        let src = assemble(&format!("{pass}.wgsl"), prelude)?;
        if regroups(pass) {
            return Ok(src + &queued_rebuild_entries());
        }
        return Ok(src);
    };
    let order = resolve_each(&pass_files(pass))?;
    let members: Vec<&str> = fused.members().map(|s| s.name).collect();
    let body = concatenate(String::new(), &order) + &fused_entry(pass, &members);
    Ok(format!("{}{body}", used_size_classes_only(prelude, &body)))
}

/// [`assemble_pass`] of a pass that [`rebuilds_resets`] for a batch whose reset-pool rows leave
/// their ORCA obstacles to the device: the pass's files after the obstacle library's, then the
/// rebuild entry points over the environments it reset. An error for any other pass.
pub fn assemble_pass_rebuilding_resets(pass: &str, prelude: &str) -> Result<String, String> {
    if !rebuilds_resets(pass) {
        return Err(format!("pass {pass:?} resets no environment from the pool"));
    }
    let files = [
        "common/orca_obstacles.wgsl".to_owned(),
        format!("{pass}.wgsl"),
    ];
    let body = concatenate(String::new(), &resolve_each(&files)?) + &reset_rebuild_entries(pass);
    Ok(format!("{}{body}", used_size_classes_only(prelude, &body)))
}

/// `prelude` without the declaration of each size class that neither `body` nor the rest of the
/// prelude names.
fn used_size_classes_only(prelude: &str, body: &str) -> String {
    let declaration = |name: &str| format!("const {name}: ");
    let unused: Vec<String> = SIZE_CLASS_NAMES
        .iter()
        .filter(|name| {
            !body.contains(*name)
                && !prelude
                    .lines()
                    .any(|l| l.contains(*name) && !l.starts_with(&declaration(name)))
        })
        .map(|name| declaration(name))
        .collect();
    let mut out = String::with_capacity(prelude.len());
    for line in prelude.lines() {
        if !unused.iter().any(|d| line.starts_with(d.as_str())) {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// The complete source of a standalone shader ([`is_standalone`]): [`standalone_head`], its
/// requirements, then the file.
pub fn assemble_standalone(path: &str) -> Result<String, String> {
    Ok(concatenate(standalone_head(), &resolve(path)?))
}

/// The generated head of the standalone shaders ([`is_standalone`]), which have no batch prelude:
/// [`geometry_constants`] (common/geometry.wgsl needs them) and the constants SNGNN-v2's network
/// shares with the Rust side, from their Rust definitions: the packed graph words (`G_NODES`,
/// `G_EDGES`, `G_SRC`, [`crate::sngnn::packed::words`]), `NODE_FEATURES` and `RELATIONS`
/// ([`crate::sngnn`]), the words of a relation's table entry (`T_*`,
/// [`crate::sngnn::pieces::flat`]) and the status bits the host reads back (`STATUS_*`,
/// [`sngnn_status`]).
#[expect(clippy::expect_used, reason = "the constants are small table indices")]
pub fn standalone_head() -> String {
    use crate::sngnn::{NODE_FEATURES, RELATIONS, packed::words, pieces::flat};
    let mut out = String::from("// Generated by src/backend/wgsl.rs (standalone head).\n");
    out.push_str(&geometry_constants());
    let index = |i: usize| u32::try_from(i).expect("a small index");
    for (name, value) in [
        ("G_NODES", index(words::NODES)),
        ("G_EDGES", index(words::EDGES)),
        ("G_SRC", index(words::SRC)),
        ("NODE_FEATURES", index(NODE_FEATURES)),
        ("RELATIONS", index(RELATIONS)),
        ("T_ZERO", index(flat::ZERO)),
        ("T_KNOTS", index(flat::KNOTS)),
        ("T_AT", index(flat::AT)),
        ("T_VALUES", index(flat::VALUES)),
        ("T_WORDS", index(flat::WORDS)),
        ("STATUS_UNSUPPORTED", sngnn_status::UNSUPPORTED),
        ("STATUS_BAD_GRAPH", sngnn_status::BAD_GRAPH),
        ("STATUS_EMPTY", sngnn_status::EMPTY),
    ] {
        out.push_str(&format!("const {name}: u32 = {value}u;\n"));
    }
    out
}

/// The status bits `shaders/sngnn_score.wgsl` leaves per environment, which the GPU backend's SNGNN
/// host (`backend::gpu::sngnn_net`) reads back. Here, outside the `gpu` feature, so that
/// [`standalone_head`] writes them into the shader from these values.
pub mod sngnn_status {
    /// An edge distance lies outside the edge-weight tables (the device has no edge network).
    pub const UNSUPPORTED: u32 = 1;
    /// The graph exceeds its packed layout or names a node or relation that does not exist.
    pub const BAD_GRAPH: u32 = 2;
    /// Not an error: the graph has no nodes, so the environment is not scored.
    pub const EMPTY: u32 = 4;
}

/// `StepParams` in WGSL, generated from the Rust declaration
/// ([`crate::params::StepParams::WGSL_FIELDS`]) so that it is written once: one member per Rust
/// field, in the same order, with the Rust name (`_pad` is `pad`). The Rust struct's arrays,
/// two-component ones included, are flat here (`counts[2 * k]` is `counts[k][0]`).
///
/// The shaders bind it read-only as storage (`params`), not as a uniform buffer: a uniform array
/// needs a 16-byte element stride, and the Rust struct packs its arrays at 4 bytes. In storage,
/// every member (a 4-byte scalar or an array of them) is 4-byte aligned with a 4-byte stride, as in
/// the `#[repr(C)]` struct; tests/suite/foundations/shaders_validate.rs checks the offsets and size
/// naga computes against Rust's.
pub fn step_params_struct() -> String {
    let mut out = String::from("struct StepParams {\n");
    for f in crate::params::StepParams::WGSL_FIELDS {
        out.push_str(&format!("    {}: {},\n", f.wgsl_name(), f.wgsl_type()));
    }
    out.push_str("}\n");
    out
}

/// The constants of `shaders/common/geometry.wgsl`, generated from their Rust definitions in
/// [`crate::geometry`] so that they are written once: the contact-shape codes
/// (`GEO_CONTACT_EXACT`, `GEO_CONTACT_POLYGON64`) and the 64-gon's cosine table and early-answer
/// factors (`GEO_POLY64_COS`, `GEO_POLY64_OUTER`, `GEO_POLY64_INNER`), floats as exact
/// hexadecimal literals.
pub fn geometry_constants() -> String {
    use crate::geometry::{POLY64_COS, POLY64_INNER, POLY64_OUTER, contact_shape};
    let table: Vec<String> = POLY64_COS.iter().map(|&v| wgsl_f32(v)).collect();
    format!(
        "const GEO_CONTACT_EXACT: u32 = {}u;\nconst GEO_CONTACT_POLYGON64: u32 = {}u;\n\
         const GEO_POLY64_OUTER: f32 = {};\nconst GEO_POLY64_INNER: f32 = {};\n\
         const GEO_POLY64_COS = array<f32, {}>({});\n",
        contact_shape::EXACT,
        contact_shape::POLYGON64,
        wgsl_f32(POLY64_OUTER),
        wgsl_f32(POLY64_INNER),
        POLY64_COS.len(),
        table.join(", ")
    )
}

/// A finite f32 as the WGSL literal that denotes exactly its bits: `0.0f` for zero, otherwise a
/// hexadecimal float (`-0x1.921fb6p1f`); a decimal literal is parsed as an abstract float and
/// could round differently.
pub fn wgsl_f32(v: f32) -> String {
    assert!(
        v.is_normal() || v == 0.0,
        "{v} has no plain hexadecimal literal"
    );
    let bits = v.to_bits();
    let sign = if bits >> 31 == 1 { "-" } else { "" };
    if v == 0.0 {
        return format!("{sign}0.0f");
    }
    let exp = ((bits >> 23) & 0xff) as i32 - 127;
    // 23 fraction bits, shifted to fill 6 hexadecimal digits.
    let frac = (bits & 0x7f_ffff) << 1;
    format!("{sign}0x1.{frac:06x}p{exp}f")
}

/// `head`, then the embedded files `order`, each after a line naming it.
#[expect(
    clippy::expect_used,
    reason = "`order` comes from `resolve`, which lists embedded files only"
)]
fn concatenate(mut src: String, order: &[&str]) -> String {
    for p in order {
        src.push_str(&format!("// ---- shaders/{p}\n"));
        src.push_str(source(p).expect("resolved files are embedded"));
        src.push('\n');
    }
    src
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pool's layout in the batch uniform follows where its rows' obstacles are built: rows
    /// that leave them to the device are [`POOL_OBSTACLE_COLUMNS`]' words shorter, in their state
    /// part, as the host writes them (`reset_pool::row_words`), and every one of those names is a
    /// state column (a renamed column would otherwise stay in the rows unnoticed).
    #[test]
    fn the_pool_layout_follows_where_obstacles_are_built() {
        use crate::backend::{obs_payload, reset_pool};
        let config = crate::config::Config::from_name_or_path("exp2").expect("shipped config");
        let caps = crate::state::Caps::from_config(&config);
        let obs = crate::spec::ObsLayout::new(&caps, &config.observation);
        let state = crate::state::BatchState::new(0, caps).columns();
        let outputs = obs_payload::device_columns(&crate::outputs::Outputs::new(0, obs));
        let obstacle_words: usize = POOL_OBSTACLE_COLUMNS
            .iter()
            .map(|name| {
                let column = state.iter().find(|c| c.0 == *name);
                column
                    .unwrap_or_else(|| panic!("{name} is no state column"))
                    .2
            })
            .sum();
        assert_eq!(obstacle_words, 7 * caps.obstacle_vertices + 1);
        let layout = BatchLayout::new(5, &state, &outputs, &obs, None);
        for (build, held) in [(ObstacleBuild::Now, 1), (ObstacleBuild::Deferred, 0)] {
            let words = pool_row_words(&state, &outputs, build);
            assert_eq!(words, reset_pool::row_words(caps, obs, build), "{build:?}");
            let l = layout.clone().with_pool_obstacles(build);
            assert_eq!(l.get("pool_row"), Some(words as u32), "{build:?}");
            assert_eq!(l.get("pool_obstacles"), Some(held), "{build:?}");
            let observation = words - pool_outputs(&outputs).map(|c| c.2).sum::<usize>();
            assert_eq!(
                l.get("pool_observation"),
                Some(observation as u32),
                "{build:?}"
            );
        }
        assert_eq!(
            pool_row_words(&state, &outputs, ObstacleBuild::Now)
                - pool_row_words(&state, &outputs, ObstacleBuild::Deferred),
            obstacle_words
        );
    }

    /// A function left out returns at once with its type's zero value, whatever that type (none,
    /// a scalar, a vector, a struct), the shader still validates, and the names it does not
    /// define are not found.
    #[test]
    fn functions_left_out_return_at_once() {
        let src = "struct Pair {\n    a: f32,\n    b: bool,\n}\n\
                   fn none(x: u32) {\n    let y = x;\n}\n\
                   fn scalar(x: array<u32, 2>) -> u32 {\n    return x[0];\n}\n\
                   fn vector() -> vec2<f32> {\n    return vec2<f32>(1.0, 2.0);\n}\n\
                   fn pair() -> Pair {\n    return Pair(1.0, true);\n}\n\
                   @compute @workgroup_size(1)\nfn main() {\n    none(scalar(array<u32, 2>(1u, 2u)));\n    let v = vector();\n    let p = pair();\n}\n";
        let names: Vec<String> = ["none", "scalar", "vector", "pair", "absent", "mai"]
            .map(String::from)
            .to_vec();
        let (out, found) = with_functions_returning_at_once(src, &names);
        assert_eq!(found, ["none", "scalar", "vector", "pair"]);
        for line in [
            "fn none(x: u32) {\n    return; // left out",
            "-> u32 {\n    return u32(); // left out",
            "-> vec2<f32> {\n    return vec2<f32>(); // left out",
            "-> Pair {\n    return Pair(); // left out",
        ] {
            assert!(out.contains(line), "{line:?} in\n{out}");
        }
        let module = naga::front::wgsl::parse_str(&out).expect("parses");
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .expect("validates");
    }

    /// The poisoned build differs from the normal one exactly in the constant that turns the
    /// ORCA lists' poison on, which every prelude declares once.
    #[test]
    fn poisoning_turns_the_one_constant() {
        let head = shared_head();
        assert_eq!(head.matches(ORCA_LISTS_KEPT).count(), 1);
        let poisoned = with_poisoned_orca_lists(&head);
        assert_eq!(
            poisoned,
            head.replace(
                "ORCA_POISON_LISTS: bool = false",
                "ORCA_POISON_LISTS: bool = true"
            )
        );
        assert_ne!(poisoned, head);
    }

    /// The WGSL types come from the Rust types through `WgslValue`, with no annotation: scalars
    /// keep their type, arrays (two-component ones included) are flat, and `_pad` is `pad`, as
    /// the shaders read them.
    #[test]
    fn step_params_struct_maps_the_rust_types() {
        let src = step_params_struct();
        for member in [
            "    dt: f32,\n",
            "    episode_length: u32,\n",
            "    size_x_min: i32,\n",
            "    counts: array<i32, 24>,\n",
            "    obs_noise: array<f32, 12>,\n",
            "    pad: array<u32, 2>,\n",
        ] {
            assert!(src.contains(member), "{member:?} missing from:\n{src}");
        }
        assert_eq!(
            src.lines().count(),
            crate::params::StepParams::WGSL_FIELDS.len() + 2
        );
    }
}
