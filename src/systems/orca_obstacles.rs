//! The ORCA obstacles of an environment, processed as RVO2's `processObstacles` does (which may
//! split edges) and stored in the `ov_*` columns. They change only when an obstacle appears or
//! disappears (a reset, a laptop user or a standing group forming or leaving), so they are rebuilt
//! only when `obstacles_dirty` is set, not every step.
//!
//! The polygons, in 0.1.1's order: tables, free laptops, plants (bounding squares), walls, laptop
//! users (axis-aligned squares of half-side `laptop_user_half_side`, 2 x human diameter in 0.1.1)
//! and standing groups (squares of half-side the group radius around the stored centre).
//!
//! A walker whose field of view is narrower than 0.1.1's "sees everything" tolerance takes part
//! only with the obstacles it sees (docs/spec.md 4.2-4.3): [`with_visible`] processes that subset,
//! in the same order, for its one solve. Both paths walk the one list of [`for_each_polygon`].

use std::cell::RefCell;

use crate::error::SimError;
use crate::fixed::Fixed;
use crate::geometry::{Disc, Rect, Shape};
use crate::limits::MAX_POLYGONS;
use crate::orca::{
    OBSTACLE_REJECT_FACTOR, ObstacleScratch, ObstacleSet, ObstacleVerts, OrcaAgent,
    first_zero_length_edge, obstacle_range_sq, process_obstacles,
};
use crate::params::StepParams;
use crate::state::{NONE, StateChunk, group_kind};

use super::perception::{self, View};

type Polygon = [[f32; 2]; 4];

thread_local! {
    static BUILD: RefCell<(ObstacleScratch, ObstacleSet)> = RefCell::new(Default::default());
}

/// `obstacles_dirty` after a rebuild whose processed set did not fit the environment's
/// capacity ([`rebuild_if_dirty`]); the shaders' `ORCA_OBSTACLES_FAILED`.
pub const OBSTACLES_FAILED: u32 = 2;

/// The bits of the NaN a failed rebuild leaves in the obstacle columns: `math_nan()` of
/// `shaders/common/math.wgsl`, so that both backends leave the same bits.
const POISON_BITS: u32 = 0x7fc0_0000;

/// Rebuild the processed obstacles of environment `e` if they are stale. Where the processed set
/// is larger than the environment's capacity (RVO2 splits an edge wherever a splitting line
/// crosses it, so overlapping obstacles can split each other's edges many times over: a state
/// edited or loaded with overlapping tables can need more than `Caps` allows; no scene a config
/// generates does, `tests/suite/whole_step/scenario_props.rs`), the columns are poisoned as the
/// shaders poison them (every slot NaN, in one ring of the whole capacity), `obstacles_dirty`
/// is left at [`OBSTACLES_FAILED`], and the vertices the set needed are returned.
pub fn rebuild_if_dirty(p: &StepParams, s: &mut StateChunk, e: usize) -> Option<usize> {
    if s.obstacles_dirty[e] == 0 {
        return None;
    }
    let mut polygons: Fixed<Polygon, MAX_POLYGONS> = Fixed::default();
    for_each_polygon(p, s, e, |_, polygon| polygons.push(polygon));
    let cap = s.strides.obstacle_vertices;
    let needed = with_processed(cap, polygons.as_slice(), |set| {
        if set.len() > cap {
            poison(s, e);
            return Some(set.len());
        }
        store(s, e, set);
        None
    });
    s.obstacles_dirty[e] = if needed.is_some() {
        OBSTACLES_FAILED
    } else {
        0
    };
    needed
}

/// Rebuild environment `e`'s obstacles (of a state edited or loaded, outside a step) if they are
/// stale, `env` being its index in the batch.
///
/// # Errors
/// `SimError::Shape` naming the vertices needed and the capacity where the processed set does
/// not fit (the environment is left as [`rebuild_if_dirty`] leaves it).
pub fn rebuild_edited(
    p: &StepParams,
    s: &mut StateChunk,
    e: usize,
    env: usize,
) -> Result<(), SimError> {
    match rebuild_if_dirty(p, s, e) {
        None => Ok(()),
        Some(needed) => Err(SimError::shape(
            "state",
            format!(
                "environment {env}: its ORCA obstacles need {needed} processed vertices, more \
                 than the {} this config holds (RVO2 splits an obstacle's edge wherever another \
                 obstacle's edge line crosses it, and overlapping tables, laptops or plants do \
                 so many times over): move them apart",
                s.strides.obstacle_vertices
            ),
        )),
    }
}

/// What the shaders store for a processed set that overflowed (`orca_obstacles_store_part` in
/// `shaders/common/orca_obstacles.wgsl`): every slot of the capacity NaN, linked in one ring,
/// convex.
fn poison(s: &mut StateChunk, e: usize) {
    let cap = s.strides.obstacle_vertices;
    let nan = f32::from_bits(POISON_BITS);
    let b = e * cap;
    for k in 0..cap {
        let i = b + k;
        s.ov_x[i] = nan;
        s.ov_y[i] = nan;
        s.ov_dir_x[i] = nan;
        s.ov_dir_y[i] = nan;
        s.ov_next[i] = ((k + 1) % cap) as u32;
        s.ov_prev[i] = ((k + cap - 1) % cap) as u32;
        s.ov_convex[i] = 1;
    }
    s.n_obstacle_vertices[e] = cap as u32;
}

/// The processed ORCA obstacles of environment `e`.
pub fn obstacles<'s>(s: &'s StateChunk, e: usize) -> ObstacleVerts<'s> {
    let b = e * s.strides.obstacle_vertices;
    let n = b + s.n_obstacle_vertices[e] as usize;
    ObstacleVerts {
        x: &s.ov_x[b..n],
        y: &s.ov_y[b..n],
        dir_x: &s.ov_dir_x[b..n],
        dir_y: &s.ov_dir_y[b..n],
        next: &s.ov_next[b..n],
        prev: &s.ov_prev[b..n],
        convex: &s.ov_convex[b..n],
    }
}

/// Run `f` on the processed obstacles of environment `e` that `view` sees, for `agent`'s solve:
/// the cached set when it sees them all (bit for bit what a walker seeing everything gets); no
/// obstacles when none it sees comes within its obstacle range (split edges are pieces of the
/// input edges, so none of them would be a neighbour either: the same velocity); else the visible
/// polygons, in the same order, processed afresh into this thread's buffers (reserved from the
/// capacities, so a warm step does not allocate).
pub fn with_visible<R>(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    view: &View,
    agent: &OrcaAgent,
    f: impl FnOnce(&ObstacleVerts<'_>) -> R,
) -> R {
    // As RVO2's neighbour search, with a margin so that f32 rounding of the bounding-box distance
    // never calls far a polygon whose edges the search would accept.
    let range_sq = obstacle_range_sq(agent.time_horizon_obst, agent.max_speed, agent.radius);
    let reject_sq = range_sq * OBSTACLE_REJECT_FACTOR;
    let mut polygons: Fixed<Polygon, MAX_POLYGONS> = Fixed::default();
    let (mut all, mut near) = (0, false);
    for_each_polygon(p, s, e, |seen_as, polygon| {
        all += 1;
        if view.sees(&seen_as) {
            near |= box_distance_sq(agent.pos, &polygon) <= reject_sq;
            polygons.push(polygon);
        }
    });
    if polygons.len() == all {
        return f(&obstacles(s, e));
    }
    if !near {
        return f(&ObstacleVerts::EMPTY);
    }
    with_processed(s.strides.obstacle_vertices, polygons.as_slice(), |set| {
        f(&set.as_view())
    })
}

/// Squared distance (m²) from `pos` to the bounding box of `polygon` (0 inside).
fn box_distance_sq(pos: [f32; 2], polygon: &Polygon) -> f32 {
    let gap = |k: usize| {
        let lo = polygon[1..].iter().fold(polygon[0][k], |m, v| m.min(v[k]));
        let hi = polygon[1..].iter().fold(polygon[0][k], |m, v| m.max(v[k]));
        (lo - pos[k]).max(pos[k] - hi).max(0.0)
    };
    let (dx, dy) = (gap(0), gap(1));
    dx * dx + dy * dy
}

/// Process `polygons` with RVO2's `processObstacles` into this thread's set and run `f` on it;
/// `cap` is the environment's obstacle-vertex capacity.
#[expect(
    clippy::panic,
    reason = "validated configs (sizes resolvable at the room's extent) and checked state documents (positions inside the room) give no degenerate polygon"
)]
fn with_processed<R>(cap: usize, polygons: &[Polygon], f: impl FnOnce(&ObstacleSet) -> R) -> R {
    BUILD.with(|b| {
        let (scratch, set) = &mut *b.borrow_mut();
        // Reserved from the capacities on a thread's first build, so no later build allocates.
        set.reserve(cap);
        scratch.reserve(cap);
        // The scene's obstacles have a direction on every edge by construction (tables, laptops
        // and squares of positive size, validated where configs and documents are read), as
        // RVO2's arithmetic on a zero-length edge would make NaN directions.
        if let Some((polygon, vertex)) = first_zero_length_edge(polygons) {
            panic!(
                "scenario produced a zero-length obstacle edge: polygon {polygon} vertex {vertex}"
            );
        }
        process_obstacles(polygons, scratch, set)
            .unwrap_or_else(|err| panic!("scenario produced an invalid obstacle: {err}"));
        f(set)
    })
}

/// Every ORCA obstacle polygon of environment `e`, in 0.1.1's order, with the shape a walker's
/// field of view is tested against (`perception.rs`): rectangles as themselves, plants, laptop
/// users and standing groups as the discs 0.1.1 tests (their polygons are squares).
pub fn for_each_polygon(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    mut f: impl FnMut(Shape, Polygon),
) {
    for t in 0..s.n_tables[e] as usize {
        let r = super::world::table_rect(p, s, e, t);
        f(Shape::Rect(r), corners(&r));
    }
    let lb = e * s.strides.laptops;
    for l in 0..s.n_laptops[e] as usize {
        if s.l_user[lb + l] == NONE {
            let r = super::world::laptop_rect(p, s, e, l);
            f(Shape::Rect(r), corners(&r));
        }
    }
    let pb = e * s.strides.plants;
    for i in pb..pb + s.n_plants[e] as usize {
        let (x, y, r) = (s.p_x[i], s.p_y[i], p.plant_radius);
        f(Shape::Disc(Disc { x, y, r }), square(x, y, r));
    }
    for w in 0..s.n_walls[e] as usize {
        let r = super::world::wall_rect(p, s, e, w);
        f(Shape::Rect(r), corners(&r));
    }
    let hb = e * s.strides.humans;
    let ub = e * s.strides.laptop_users;
    for u in ub..ub + s.n_laptop_users[e] as usize {
        let h = hb + s.lu_human[u] as usize;
        let seen_as = Shape::Disc(perception::laptop_use_disc(p, s, e, u));
        f(seen_as, square(s.h_x[h], s.h_y[h], p.laptop_user_half_side));
    }
    let gb = e * s.strides.groups;
    for g in gb..gb + s.n_groups[e] as usize {
        if s.g_kind[g] == group_kind::STANDING {
            let seen_as = Shape::Disc(perception::group_disc(p, s, g));
            f(seen_as, square(s.g_x[g], s.g_y[g], p.group_radius));
        }
    }
}

/// The rectangle's corners in 0.1.1's counter-clockwise order.
fn corners(r: &Rect) -> Polygon {
    [0, 1, 2, 3].map(|k| r.corner(k).into())
}

/// The axis-aligned square of half-side `h` around (x, y), counter-clockwise from (+h, +h).
fn square(x: f32, y: f32, h: f32) -> Polygon {
    [
        [x + h, y + h],
        [x - h, y + h],
        [x - h, y - h],
        [x + h, y - h],
    ]
}

/// Store processed set `set`, which fits the capacity ([`rebuild_if_dirty`] checks).
fn store(s: &mut StateChunk, e: usize, set: &ObstacleSet) {
    let cap = s.strides.obstacle_vertices;
    let v = set.as_view();
    let b = e * cap;
    let n = set.len();
    // A smaller set than before (a laptop user stood up): its old tail becomes unused slots,
    // which hold zeros (crate::state).
    zero_from(s, e, n);
    s.ov_x[b..b + n].copy_from_slice(v.x);
    s.ov_y[b..b + n].copy_from_slice(v.y);
    s.ov_dir_x[b..b + n].copy_from_slice(v.dir_x);
    s.ov_dir_y[b..b + n].copy_from_slice(v.dir_y);
    s.ov_next[b..b + n].copy_from_slice(v.next);
    s.ov_prev[b..b + n].copy_from_slice(v.prev);
    s.ov_convex[b..b + n].copy_from_slice(v.convex);
    s.n_obstacle_vertices[e] = n as u32;
}

/// Empty the processed obstacles of environment `e`: no vertices, every slot zero, as a fresh
/// table holds them (a reset that leaves the build to later: `reset::ObstacleBuild::Deferred`).
pub fn clear(s: &mut StateChunk, e: usize) {
    zero_from(s, e, 0);
    s.n_obstacle_vertices[e] = 0;
}

/// Zero environment `e`'s obstacle slots from `n` to its current count (unused slots hold zeros:
/// crate::state).
fn zero_from(s: &mut StateChunk, e: usize, n: usize) {
    let cap = s.strides.obstacle_vertices;
    let old = (s.n_obstacle_vertices[e] as usize).min(cap);
    if old > n {
        let b = e * cap;
        let tail = b + n..b + old;
        s.ov_x[tail.clone()].fill(0.0);
        s.ov_y[tail.clone()].fill(0.0);
        s.ov_dir_x[tail.clone()].fill(0.0);
        s.ov_dir_y[tail.clone()].fill(0.0);
        s.ov_next[tail.clone()].fill(0);
        s.ov_prev[tail.clone()].fill(0);
        s.ov_convex[tail].fill(0);
    }
}
