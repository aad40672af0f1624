//! The batch's layout as the shaders see it: the uniform `batch` (`BatchLayout`: offsets and strides
//! of every column, generated from the state's column list), the device's element order, the
//! scratch regions, the observation's rows, the reset pool's rows and the slot permutations' words,
//! and the size classes that let one shader text serve every shipped config.

use super::WORKGROUP_SIZE;
use crate::state::columns::{Elem, ElementOrder};
use crate::systems::reset::ObstacleBuild;

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
pub(super) fn slot_index_functions(state: Columns<'_>) -> String {
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
/// `prelude`: `n_envs`; for each state column its first word `c_<name>` in the packed buffer
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
    /// place: `obs_staged` (see [`scratch_words`], `GpuPaths::stage_observations`).
    pub fn with_staged_observation(self, on: bool) -> Self {
        self.with_flag("obs_staged", on)
    }

    /// This layout with the observation's entity records written by [`OBS_RECORDS_ENTRY`], a lane
    /// each, in a whole view (`on`), or by the observing lane: `obs_records_apart`
    /// (`GpuPaths::records_in_lanes`).
    pub fn with_records_apart(self, on: bool) -> Self {
        self.with_flag("obs_records_apart", on)
    }

    /// This layout with reset-pool rows whose ORCA obstacles are built as `obstacles` says:
    /// `pool_obstacles` 0, and `pool_row` and `pool_observation` without the words of
    /// [`POOL_OBSTACLE_COLUMNS`], where the rows leave them to the device
    /// (`GpuPaths::obstacles_after_resets`).
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

/// One environment's region of the `scratch` buffer (binding 8 of `prelude`), the working
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
pub(super) fn sngnn_sizes(sngnn: Option<SngnnSizes<'_>>) -> Vec<(String, usize)> {
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
pub(super) fn size_class(n: usize, floor: usize) -> usize {
    n.max(floor).next_power_of_two()
}

/// The output columns a reset writes from the pool (the first observation of an episode); the
/// rest of what a reset writes (reward, flags, info) are constants.
pub const POOL_OUTPUT_COLUMNS: [&str; 5] =
    ["obs", "obs_count", "hh_pairs", "hl_pairs", "pair_count"];

/// The state columns of an environment's processed ORCA obstacles, which a reset-pool row that
/// leaves them to the device ([`ObstacleBuild::Deferred`]) does not hold: two fifths of an exp2
/// row, which the host would write, the device's pool keep and every reset copy, only for the
/// rebuild to replace. Such a row's copy leaves the environment's old obstacles in place, their
/// count included, and the rebuild after it (`rebuilds_resets`: the submit's one rebuild
/// of the `REBUILD_QUEUE`, or the reset pass's own) replaces them, zeroing the old tail past
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
pub(super) fn pool_state_words(state: Columns<'_>, obstacles: ObstacleBuild) -> usize {
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
pub(super) fn pool_outputs<'a>(
    outputs: Columns<'a>,
) -> impl Iterator<Item = &'a (&'static str, Elem, usize)> + Clone {
    POOL_OUTPUT_COLUMNS.iter().map(move |name| {
        outputs
            .iter()
            .find(|c| c.0 == *name)
            .expect("the pool's output columns exist")
    })
}

/// The slot kinds whose slots the social events reorder, with the WGSL name of their permutation.
pub(super) const PERMUTED_KINDS: [(&str, &str); 4] = [
    ("human", "state_permute_humans"),
    ("group", "state_permute_groups"),
    ("laptop_user", "state_permute_laptop_users"),
    ("laptop", "state_permute_laptops"),
];

/// The kind of state column `col` (`human`, `group`, ...), from `soa!`'s declaration.
pub(super) fn kind_of(col: &str) -> Option<&'static str> {
    crate::state::BatchState::COLUMN_KINDS
        .iter()
        .find(|&&(c, _)| c == col)
        .map(|&(_, k)| k)
}

/// The largest capacity of the kinds the social events reorder (0 if none).
pub(super) fn permuted_cap(state: Columns<'_>) -> usize {
    PERMUTED_KINDS
        .iter()
        .flat_map(|&(kind, _)| columns_of(state, kind))
        .map(|&(_, _, stride)| stride)
        .max()
        .unwrap_or(0)
}

/// The state columns of slot kind `kind`, in declaration order.
pub(super) fn columns_of<'a>(
    state: Columns<'a>,
    kind: &str,
) -> Vec<&'a (&'static str, Elem, usize)> {
    state
        .iter()
        .filter(|c| kind_of(c.0) == Some(kind))
        .collect()
}

/// Words of the `scratch` region the slot permutations of environment `e` pass their old slots
/// through ([`permute_functions`]): a part for each kind, a word per column and slot, so that a
/// regrouping on a workgroup's lanes moves every kind's slots at once.
pub(super) fn permute_words(state: Columns<'_>) -> usize {
    permute_parts(state)
        .last()
        .map_or(0, |&(at, words)| at + words)
}

/// Where each kind of [`PERMUTED_KINDS`] keeps its old slots in an environment's region of
/// `scratch`, and how many words they take: (offset, words), the kinds end to end.
pub(super) fn permute_parts(state: Columns<'_>) -> Vec<(usize, usize)> {
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
}
