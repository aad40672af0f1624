//! The batch prelude every stage's shader starts with, generated from Rust so that nothing is
//! written twice: the shared constants, `StepParams` in WGSL, the size classes, the rare-work queues,
//! the slot permutations and the reset pool's copies; and the documented rewrites of a prelude or a
//! pass (poisoned ORCA lists, regroupings and resets on a workgroup's lanes, functions left out).

use super::WORKGROUP_SIZE;
use super::bindings::{BATCH_BINDINGS, SNGNN_GRAPH_BINDINGS, declarations};
use super::layout::{
    BatchLayout, Columns, OBS_ROWS_TILE, PERMUTED_KINDS, SIZE_CLASS_NAMES, SizeClasses, columns_of,
    slot_index_functions,
};
use super::pool::pool_functions;
use crate::backend::schedule::{RARE_QUEUES, REBUILD_QUEUE};
use crate::state::columns::Elem;

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
pub(super) const ORCA_LISTS_KEPT: &str = "const ORCA_POISON_LISTS: bool = false;\n";

/// `src` (a prelude, or a shader assembled from one) with the ORCA lists poisoned at every clear:
/// every entry NaN, every index one no list holds (`GpuPaths::poison_orca_lists`, for the test
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
pub(super) const RESETS_BY_ONE_LANE: &str = "const RESET_LANES: u32 = 1u;\n";

/// The line of [`shared_head`] that gives each regrouping of a step's social events and
/// formations one lane (`shaders/common/regroup.wgsl`); [`with_regroups_in_workgroups`] turns it.
pub(super) const REGROUPS_BY_ONE_LANE: &str = "const REGROUP_LANES: u32 = 1u;\n";

/// Bytes of workgroup memory a regrouping on a workgroup's lanes takes with these size classes
/// (`shaders/common/regroup.wgsl`'s `regroup_wg_*`: the four kinds' sort keys (four words each),
/// sorted slots and inverses, each group's members and first member, a few words): with
/// `PERMUTE_CAP` 64, 6.6 KiB.
pub fn regroup_workgroup_bytes(classes: &SizeClasses) -> usize {
    4 * (26 * classes.permute + 4 + 4 + 4 + 2 + 1)
}

/// `src` (a prelude, or a shader assembled from one) with each environment that `formation` and
/// `social_events` work on taken by all the lanes of a workgroup, its regroupings shared out
/// among them (`GpuPaths::regroups_in_workgroups`, where [`regroup_workgroup_bytes`] fits the
/// device).
pub fn with_regroups_in_workgroups(src: &str) -> String {
    src.replacen(
        REGROUPS_BY_ONE_LANE,
        "const REGROUP_LANES: u32 = WORKGROUP_SIZE;\n",
        1,
    )
}

/// `src` (a prelude, or a shader assembled from one) with each reset of a step run by all the
/// lanes of a workgroup (`GpuPaths::resets_in_workgroups`).
pub fn with_resets_in_workgroups(src: &str) -> String {
    src.replacen(
        RESETS_BY_ONE_LANE,
        "const RESET_LANES: u32 = WORKGROUP_SIZE;\n",
        1,
    )
}

/// `src` (a shader) with each function of `names` that it defines returning at once: nothing, or
/// its return type's zero value (`T()`). For diagnosis only (`GpuPaths::leave_out`): a pass
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
/// `DEVICE_ORDER`), the slot permutations of the social events (`state_permute_*`, generated by
/// `permute_functions`), the queues of the rare work (`schedule::has_rare_work`) and the reset
/// pool's copies (`pool_copy_*`). Only `classes` depends on the config; nothing on the batch size.
pub fn prelude(state: Columns<'_>, outputs: Columns<'_>, classes: &SizeClasses) -> String {
    let mut out = String::from("// Generated by src/backend/wgsl/prelude.rs.\n");
    out.push_str(&shared_head());
    for (name, value) in SIZE_CLASS_NAMES.into_iter().zip(classes.values()) {
        out.push_str(&format!("const {name}: u32 = {value}u;\n"));
    }
    out.push_str(&step_params_struct());
    let layout = BatchLayout::new(0, state, outputs, &crate::spec::ObsLayout::default(), None);
    out.push_str(&layout.wgsl_struct());
    out.push_str(&declarations(0, &BATCH_BINDINGS));
    out.push_str(&slot_index_functions(state));
    out.push_str(&rare_work_functions());
    out.push_str(&permute_functions(state));
    out.push_str(&pool_functions(state, outputs));
    out
}

/// The SNGNN part of a prelude, appended to [`prelude`] for the shaders that build SNGNN-v2's
/// graphs (`needs_sngnn`): the code's
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
    out.push_str(&declarations(1, &SNGNN_GRAPH_BINDINGS));
    out
}

/// The queues of the stages with rare work and the [`REBUILD_QUEUE`]: their indices `RARE_<STAGE>`
/// and `RARE_REBUILD`, the type of the binding `rare` (`BATCH_BINDINGS`), and `rare_push` (queue an environment) and
/// `rare_env` (lane `k`'s environment, or `NONE` past the queue's end).
pub(super) fn rare_work_functions() -> String {
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
         fn rare_push(queue: u32, e: u32) {{\n\
         \x20   rare.list[queue * batch.n_envs + atomicAdd(&rare.count[queue], 1u)] = e;\n}}\n\
         fn rare_env(queue: u32, k: u32) -> u32 {{\n\
         \x20   if (k >= atomicLoad(&rare.count[queue])) {{\n        return NONE;\n    }}\n\
         \x20   return rare.list[queue * batch.n_envs + k];\n}}\n",
        n = RARE_QUEUES
    ));
    out
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
pub(super) fn permute_functions(state: Columns<'_>) -> String {
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
pub(super) fn shared_constants() -> Vec<(&'static str, u32)> {
    use crate::params::AutoresetMode;
    use crate::spec::one_hot;
    use crate::state::{forming, group_kind, policy, role};
    use crate::systems;
    let index = |i: usize| u32::try_from(i).expect("a small index");
    vec![
        ("NONE", crate::state::NONE),
        // The side masks of a rebuild on a workgroup's lanes: their size is in the workgroup
        // memory the rebuild takes (`REBUILD_LANES_WORDS`).
        (
            "ORCA_OBSTACLES_MASK_WORDS",
            index(super::rebuild::REBUILD_MASK_WORDS),
        ),
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
pub(super) fn shared_f32_constants() -> Vec<(&'static str, f32)> {
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

#[cfg(test)]
mod tests {
    use super::*;

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
