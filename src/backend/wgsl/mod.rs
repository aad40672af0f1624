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
//! (`schedule::fused_passes`), whose members' files each define `fn stage_<name>(e: u32)` and
//! whose `main` is generated ([`assemble_pass`]).
//!
//! The parts: this file holds the sources and their assembly; `layout` the batch layout as the
//! shaders see it (the uniform `batch`, element order, scratch, pool rows, permutation sizes, size
//! classes); `bindings` the bind groups, declared once; `pool` the pool's copies and the generated
//! pool and finished-row passes; `rebuild` the generated obstacle rebuilds; `prelude` the generated
//! prelude and its documented rewrites. Each names only the parts before it in this list (and this
//! file's shared constants).
//!
//! This module is plain text work (no wgpu), so the naga tests can assemble and validate the
//! shaders without the `gpu` feature or a device.

use super::schedule::{pass_files, rebuilds_resets, regroups};
use crate::pipeline::FusedPass;
use rebuild::{queued_rebuild_entries, reset_rebuild_entries};

mod bindings;
mod layout;
mod pool;
mod prelude;
mod rebuild;

pub use bindings::{Access, BATCH_BINDINGS, BindingDecl, SNGNN_GRAPH_BINDINGS, declarations};
pub use layout::{
    BatchLayout, Columns, DEVICE_ORDER, OBS_RECORDS_ENTRY, OBS_ROWS_ENTRY, OBS_ROWS_STAGE,
    OBS_ROWS_TILE, ObstacleScratch, POOL_OBSTACLE_COLUMNS, POOL_OUTPUT_COLUMNS, SIZE_CLASS_NAMES,
    SizeClasses, SngnnSizes, pool_holds, pool_row_words, scratch_region_words, scratch_words,
    slot_kinds,
};
pub use pool::{
    FINISHED_ROWS_PASS, POOL_RUN_WORDS, POOL_SCATTER_PASS, POOL_SCATTER_PIECE_WORDS,
    finished_columns, finished_row_words, finished_rows_shader, pool_scatter_shader,
};
pub use prelude::{
    geometry_constants, prelude, regroup_workgroup_bytes, shared_head, sngnn_prelude,
    step_params_struct, wgsl_f32, with_functions_returning_at_once, with_poisoned_orca_lists,
    with_regroups_in_workgroups, with_resets_in_workgroups,
};
pub use rebuild::{
    OBSTACLES_IN_WORKGROUP_WORDS, REBUILD_ENTRY, REBUILD_IN_WORKGROUPS_ENTRY, REBUILD_LANES_WORDS,
    REBUILD_MASK_WORDS, REBUILD_WORKGROUP_WORDS, with_obstacles_in_workgroup,
};

/// Every WGSL file under `shaders/`, by path relative to it.
pub const FILES: &[(&str, &str)] = &[
    (
        "common/math.wgsl",
        include_str!("../../../shaders/common/math.wgsl"),
    ),
    (
        "common/rng.wgsl",
        include_str!("../../../shaders/common/rng.wgsl"),
    ),
    (
        "common/geometry.wgsl",
        include_str!("../../../shaders/common/geometry.wgsl"),
    ),
    (
        "common/world.wgsl",
        include_str!("../../../shaders/common/world.wgsl"),
    ),
    (
        "common/motion.wgsl",
        include_str!("../../../shaders/common/motion.wgsl"),
    ),
    (
        "common/orca.wgsl",
        include_str!("../../../shaders/common/orca.wgsl"),
    ),
    (
        "robot_motion.wgsl",
        include_str!("../../../shaders/robot_motion.wgsl"),
    ),
    (
        "common/perception.wgsl",
        include_str!("../../../shaders/common/perception.wgsl"),
    ),
    (
        "common/sfm.wgsl",
        include_str!("../../../shaders/common/sfm.wgsl"),
    ),
    (
        "common/orca_world.wgsl",
        include_str!("../../../shaders/common/orca_world.wgsl"),
    ),
    (
        "common/orca_obstacles.wgsl",
        include_str!("../../../shaders/common/orca_obstacles.wgsl"),
    ),
    (
        "shadow_robot.wgsl",
        include_str!("../../../shaders/shadow_robot.wgsl"),
    ),
    (
        "group_velocities.wgsl",
        include_str!("../../../shaders/group_velocities.wgsl"),
    ),
    (
        "common/measures.wgsl",
        include_str!("../../../shaders/common/measures.wgsl"),
    ),
    (
        "termination.wgsl",
        include_str!("../../../shaders/termination.wgsl"),
    ),
    ("reward.wgsl", include_str!("../../../shaders/reward.wgsl")),
    (
        "metrics.wgsl",
        include_str!("../../../shaders/metrics.wgsl"),
    ),
    (
        "observation.wgsl",
        include_str!("../../../shaders/observation.wgsl"),
    ),
    (
        "group_motion.wgsl",
        include_str!("../../../shaders/group_motion.wgsl"),
    ),
    (
        "contacts.wgsl",
        include_str!("../../../shaders/contacts.wgsl"),
    ),
    (
        "common/pool_reset.wgsl",
        include_str!("../../../shaders/common/pool_reset.wgsl"),
    ),
    (
        "begin_step.wgsl",
        include_str!("../../../shaders/begin_step.wgsl"),
    ),
    (
        "autoreset.wgsl",
        include_str!("../../../shaders/autoreset.wgsl"),
    ),
    ("reset.wgsl", include_str!("../../../shaders/reset.wgsl")),
    (
        "sngnn_score.wgsl",
        include_str!("../../../shaders/sngnn_score.wgsl"),
    ),
    (
        "human_motion.wgsl",
        include_str!("../../../shaders/human_motion.wgsl"),
    ),
    ("goals.wgsl", include_str!("../../../shaders/goals.wgsl")),
    (
        "common/place.wgsl",
        include_str!("../../../shaders/common/place.wgsl"),
    ),
    (
        "common/goal_sampling.wgsl",
        include_str!("../../../shaders/common/goal_sampling.wgsl"),
    ),
    (
        "common/regroup.wgsl",
        include_str!("../../../shaders/common/regroup.wgsl"),
    ),
    (
        "social_events.wgsl",
        include_str!("../../../shaders/social_events.wgsl"),
    ),
    (
        "formation.wgsl",
        include_str!("../../../shaders/formation.wgsl"),
    ),
    (
        "common/sngnn_frame.wgsl",
        include_str!("../../../shaders/common/sngnn_frame.wgsl"),
    ),
    (
        "common/sngnn_graph_build.wgsl",
        include_str!("../../../shaders/common/sngnn_graph_build.wgsl"),
    ),
    (
        "sngnn_graph.wgsl",
        include_str!("../../../shaders/sngnn_graph.wgsl"),
    ),
];

/// The entry point `main` of a fused pass with `members` ([`fused_passes`]).
fn fused_entry(pass: &str, members: &[&str]) -> String {
    let mut out = format!(
        "// ---- generated by src/backend/wgsl/mod.rs: the entry point of fused pass `{pass}`\n\
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
    let mut out = String::from("// Generated by src/backend/wgsl/mod.rs (standalone head).\n");
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
