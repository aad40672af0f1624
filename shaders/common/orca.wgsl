// requires: common/math.wgsl
//
// Twin of src/orca/ (vector.rs, neighbors.rs, lines.rs, lp.rs and `compute_new_velocity` in
// mod.rs): the per-agent ORCA core exactly as RVO2 2.0.3 computes it, with brute-force neighbour
// selection. Library file (no entry points, no bindings), prepended after common/math.wgsl (for
// `math_inf`) to the shaders that move agents by ORCA. Every function mirrors its Rust twin
// expression for expression (`lp2` is `orca_lp2`, `Vec2::div_scalar` is `orca_div_scalar`, ...);
// read the Rust files for the method and change both sides in the same commit.
// tests/suite/orca/gpu.rs checks this file bit for bit against the Rust core on lavapipe.
//
// Float rules (src/orca/mod.rs): only `+ - * /`, `sqrt`, `abs` and comparisons, in RVO2's order:
// `v / s` is `inv = 1 / s` then two multiplies (`orca_div_scalar`), `normalize(v)` is
// `v / |v|` that way, dot products and determinants are spelled out (`a.x * b.x + a.y * b.y`;
// never the `dot`/`length`/`normalize` builtins), `std::min`/`max` are written as comparisons and
// branches as the Rust has them. Vector `+`, `-`, `-v` and scalar-vector `*` are component-wise
// and so equal the Rust operators. No fused multiply-add, no transcendentals. Constants that are
// not exact decimals are hexadecimal floats of the Rust f32 bits (a WGSL literal is parsed as an
// abstract float and could round differently). Mesa's NIR optimiser rewrites some float
// expressions on lavapipe (cancellations, factoring `a·c + b·c`, moving constants through sums,
// and reassociating `(a·b + c·d) + e` into `(a·b + e) + c·d` when the inner sum has one use);
// the forms here were checked bit for bit against the Rust core, and where the Rust shape would
// be rewritten (LP1's discriminant) the comment there says how it is kept. Keep the exact shape
// of every expression when editing, and do not negate float comparisons (`!(a < b)` may become
// `a >= b`, which differs for NaN).
//
// Data access. WGSL has no pointers to storage in function parameters and no dynamic arrays in
// function scope, so the library never reads a binding: a kernel supplies the data.
// * Building blocks (what a stage shader reading the packed state uses): the kernel loops over
//   its own storage and hands the library one item at a time: `orca_agent_neighbor_candidate`
//   (one other agent), `orca_obstacle_neighbor_candidate` (one edge), `orca_push_obstacle_line`
//   (the two end vertices of one selected edge, `orca_vertex`), `orca_push_agent_line` (one
//   selected neighbour), then `orca_solve` (LP2, LP3 when LP2 fails). Clear a `var` of a list
//   type before its first use and to reuse it (`orca_agent_neighbors_clear`,
//   `orca_obstacle_neighbors_clear`, `orca_lines_clear`): the GPU backend's own SPIR-V does not
//   zero them (src/backend/gpu/spirv.rs), and no function reads an entry at or past `len`.
//   (A form over function-scope copies of the agent's neighbours and its environment's
//   vertices, as Rust's `compute_new_velocity` takes them, is not kept: no stage used it, and its
//   7 KB copy per lane did not compile on NVIDIA's driver.)
// Lists live in fixed-size function-scope arrays; the limits are the ORCA_MAX_* constants below.
// Where Rust would grow a list past a limit, the result carries an ORCA_OVERFLOW_* bit and is not
// the CPU's: a stage must treat a non-zero `overflow` as an error (or bound its capacities by
// these limits on the host). Indices are u32.

// Most agent neighbours of one agent (Rust: `max_neighbors`, no limit).
const ORCA_MAX_AGENT_NEIGHBORS: u32 = 64u;
// Most obstacle edges one agent reacts to (Rust: no limit).
const ORCA_MAX_OBSTACLE_NEIGHBORS: u32 = 128u;
// Most ORCA lines of one agent: one per obstacle edge at most, plus one per agent neighbour, so
// lines never overflow when the neighbour lists do not.
const ORCA_MAX_LINES: u32 = ORCA_MAX_AGENT_NEIGHBORS + ORCA_MAX_OBSTACLE_NEIGHBORS;

const ORCA_OVERFLOW_AGENT_NEIGHBORS: u32 = 1u;
const ORCA_OVERFLOW_OBSTACLE_NEIGHBORS: u32 = 2u;
const ORCA_OVERFLOW_LINES: u32 = 4u;
const ORCA_OVERFLOW_OBSTACLE_VERTICES: u32 = 8u;

// The prelude defines ORCA_RVO_EPSILON (RVO2's RVO_EPSILON, Rust `orca::RVO_EPSILON`) and
// ORCA_OBSTACLE_REJECT_FACTOR (the obstacle prefilter's margin, Rust
// `orca::OBSTACLE_REJECT_FACTOR`) from the Rust constants.

// ---- vector.rs ----------------------------------------------------------------------------------

fn orca_dot(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.x + a.y * b.y;
}

fn orca_abs_sq(a: vec2<f32>) -> f32 {
    return orca_dot(a, a);
}

fn orca_abs(a: vec2<f32>) -> f32 {
    return sqrt(orca_abs_sq(a));
}

// RVO2's `v / s`: the reciprocal, then two multiplies.
fn orca_div_scalar(v: vec2<f32>, s: f32) -> vec2<f32> {
    let inv = 1.0 / s;
    return vec2<f32>(v.x * inv, v.y * inv);
}

fn orca_normalize(v: vec2<f32>) -> vec2<f32> {
    return orca_div_scalar(v, orca_abs(v));
}

fn orca_perp_l(v: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(-v.y, v.x);
}

fn orca_det(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

fn orca_left_of(a: vec2<f32>, b: vec2<f32>, c: vec2<f32>) -> f32 {
    return orca_det(a - c, b - a);
}

fn orca_dist_sq_point_segment(a: vec2<f32>, b: vec2<f32>, c: vec2<f32>) -> f32 {
    let r = orca_dot(c - a, b - a) / orca_abs_sq(b - a);
    if (r < 0.0) {
        return orca_abs_sq(c - a);
    } else if (r > 1.0) {
        return orca_abs_sq(c - b);
    }
    return orca_abs_sq(c - (a + r * (b - a)));
}

// ---- types (mod.rs, lines.rs, neighbors.rs, obstacles.rs) ---------------------------------------

// Rust `OrcaAgent`.
struct OrcaAgent {
    pos: vec2<f32>,
    vel: vec2<f32>,
    pref_vel: vec2<f32>,
    radius: f32,
    max_speed: f32,
    neighbor_dist: f32,
    max_neighbors: u32,
    time_horizon: f32,
    time_horizon_obst: f32,
}

// Rust `OrcaNeighbor`: a selected agent neighbour's start-of-step state.
struct OrcaNeighbor {
    pos: vec2<f32>,
    vel: vec2<f32>,
    radius: f32,
}

// Rust `Neighbor`: a sort key and the index of the agent (or the edge's start vertex).
struct OrcaNeighborKey {
    dist_sq: f32,
    index: u32,
}

// Rust `Line`: velocities left of `direction` through `point` are permitted (m/s).
struct OrcaLine {
    point: vec2<f32>,
    direction: vec2<f32>,
}

// A selected agent's neighbours, nearest first (Rust `Vec<Neighbor>` of `agent_neighbors`).
struct OrcaAgentNeighbors {
    len: u32,
    overflow: u32,
    items: array<OrcaNeighborKey, ORCA_MAX_AGENT_NEIGHBORS>,
}

// The obstacle edges an agent reacts to, nearest first (Rust `obstacle_neighbors`' output).
struct OrcaObstacleNeighbors {
    len: u32,
    overflow: u32,
    items: array<OrcaNeighborKey, ORCA_MAX_OBSTACLE_NEIGHBORS>,
}

// An agent's ORCA lines: obstacle lines first (`num_obstacle_lines` of them), then agent lines.
struct OrcaLines {
    len: u32,
    num_obstacle_lines: u32,
    overflow: u32,
    items: array<OrcaLine, ORCA_MAX_LINES>,
}

// What an obstacle line reads of one processed vertex `index`: `point(index)`, `dir(index)`,
// `is_convex(index)` and `dir(prev(index))`. Build it with `orca_vertex`.
struct OrcaVertex {
    point: vec2<f32>,
    dir: vec2<f32>,
    prev_dir: vec2<f32>,
    convex: u32,
    index: u32,
}

fn orca_vertex(index: u32, point: vec2<f32>, dir: vec2<f32>, prev_dir: vec2<f32>, convex: u32) -> OrcaVertex {
    return OrcaVertex(point, dir, prev_dir, convex, index);
}

// The new velocity (m/s); `used_lp3` is 1 if LP2 failed and LP3 computed it; `overflow` is
// the OR of the ORCA_OVERFLOW_* bits of the lists involved (0: the CPU's result).
struct OrcaResult {
    velocity: vec2<f32>,
    used_lp3: u32,
    overflow: u32,
}

// ---- neighbors.rs -------------------------------------------------------------------------------

// RVO2's `insertAgentNeighbor` (Rust `insert_agent_neighbor`). Past ORCA_MAX_AGENT_NEIGHBORS
// entries (only when `max_neighbors` exceeds it) the list keeps its nearest entries and flags
// the overflow.
fn orca_insert_agent_neighbor(
    list: ptr<function, OrcaAgentNeighbors>,
    max_neighbors: u32,
    candidate: OrcaNeighborKey,
    range_sq: ptr<function, f32>,
) {
    // Rust: `if max_neighbors == 0 || !in_range { return; }`. The float test is not negated here:
    // NIR may turn `!(a < b)` into `a >= b`, which differs for NaN.
    let in_range = candidate.dist_sq < *range_sq;
    if (max_neighbors == 0u) {
        return;
    }
    if (in_range) {
        if ((*list).len < max_neighbors) {
            if ((*list).len < ORCA_MAX_AGENT_NEIGHBORS) {
                (*list).len = (*list).len + 1u;
            } else {
                (*list).overflow = ORCA_OVERFLOW_AGENT_NEIGHBORS;
                if (candidate.dist_sq >= (*list).items[(*list).len - 1u].dist_sq) {
                    return;
                }
            }
        }
        var i = (*list).len - 1u;
        while (i != 0u && candidate.dist_sq < (*list).items[i - 1u].dist_sq) {
            (*list).items[i] = (*list).items[i - 1u];
            i = i - 1u;
        }
        (*list).items[i] = candidate;
        if ((*list).len == max_neighbors) {
            *range_sq = (*list).items[(*list).len - 1u].dist_sq;
        }
    }
}

// The search range `agent_neighbors` starts from (m²).
fn orca_agent_range_sq(neighbor_dist: f32) -> f32 {
    return neighbor_dist * neighbor_dist;
}

// One iteration of Rust `agent_neighbors`' loop: candidate `index` at `other_pos` for the agent
// at `pos`. The kernel visits the candidates in index order, skips the agent itself, and starts
// from an empty list and `range_sq = orca_agent_range_sq(neighbor_dist)` (max_neighbors 0:
// nothing is inserted).
fn orca_agent_neighbor_candidate(
    list: ptr<function, OrcaAgentNeighbors>,
    max_neighbors: u32,
    pos: vec2<f32>,
    index: u32,
    other_pos: vec2<f32>,
    range_sq: ptr<function, f32>,
) {
    let candidate = OrcaNeighborKey(orca_abs_sq(pos - other_pos), index);
    orca_insert_agent_neighbor(list, max_neighbors, candidate, range_sq);
}

// RVO2's `insertObstacleNeighbor` (Rust `insert_obstacle_neighbor`) for the edge `a -> b` that
// starts at `vertex`. Past ORCA_MAX_OBSTACLE_NEIGHBORS entries the list keeps its nearest
// entries and flags the overflow.
fn orca_insert_obstacle_neighbor(
    list: ptr<function, OrcaObstacleNeighbors>,
    vertex: u32,
    a: vec2<f32>,
    b: vec2<f32>,
    pos: vec2<f32>,
    range_sq: f32,
) {
    let dist_sq = orca_dist_sq_point_segment(a, b, pos);
    if (dist_sq < range_sq) {
        let candidate = OrcaNeighborKey(dist_sq, vertex);
        if ((*list).len < ORCA_MAX_OBSTACLE_NEIGHBORS) {
            (*list).len = (*list).len + 1u;
        } else {
            (*list).overflow = ORCA_OVERFLOW_OBSTACLE_NEIGHBORS;
            if (dist_sq >= (*list).items[(*list).len - 1u].dist_sq) {
                return;
            }
        }
        var i = (*list).len - 1u;
        while (i != 0u && dist_sq < (*list).items[i - 1u].dist_sq) {
            (*list).items[i] = (*list).items[i - 1u];
            i = i - 1u;
        }
        (*list).items[i] = candidate;
    }
}

// Rust `gap`: distance (m) from p to the interval between a and b (0 inside).
fn orca_gap(p: f32, a: f32, b: f32) -> f32 {
    var lo = b;
    if (a < b) {
        lo = a;
    }
    var hi = b;
    if (a > b) {
        hi = a;
    }
    let below = lo - p;
    let above = p - hi;
    var d = above;
    if (below > above) {
        d = below;
    }
    if (d > 0.0) {
        return d;
    }
    return 0.0;
}

// Rust `obstacle_range_sq`: `(time_horizon_obst * max_speed + radius)²` (m²).
fn orca_obstacle_range_sq(time_horizon_obst: f32, max_speed: f32, radius: f32) -> f32 {
    let range = time_horizon_obst * max_speed + radius;
    return range * range;
}

// One iteration of Rust `obstacle_neighbors`' loop: the edge from vertex `vertex` at `a` to its
// next vertex at `b`. The kernel visits the vertices in index order, from an empty list, with
// `range_sq = orca_obstacle_range_sq(...)`.
fn orca_obstacle_neighbor_candidate(
    list: ptr<function, OrcaObstacleNeighbors>,
    pos: vec2<f32>,
    range_sq: f32,
    vertex: u32,
    a: vec2<f32>,
    b: vec2<f32>,
) {
    let reject_sq = range_sq * ORCA_OBSTACLE_REJECT_FACTOR;
    let dx = orca_gap(pos.x, a.x, b.x);
    if (dx * dx > reject_sq) {
        return;
    }
    let dy = orca_gap(pos.y, a.y, b.y);
    if (dx * dx + dy * dy > reject_sq) {
        return;
    }
    let s = orca_left_of(a, b, pos);
    if (s < 0.0 && s * s / orca_abs_sq(b - a) < range_sq) {
        orca_insert_obstacle_neighbor(list, vertex, a, b, pos, range_sq);
    }
}

// ---- lines.rs -----------------------------------------------------------------------------------

// The lists' clears. Every function-scope variable of the three list types must be cleared
// before its first use: the GPU backend's own SPIR-V (src/backend/gpu/spirv.rs, `UNZEROED_TYPES`)
// does not zero them, since a call reads only the entries below the count it wrote.
// The lists' entries are left as they were (on Vulkan the backend's SPIR-V does not zero them:
// backend::gpu::spirv); no entry at or past `len` is ever read. With ORCA_POISON_LISTS (a
// generated constant, true only in the builds of the test that checks this:
// `GpuPaths::poison_orca_lists`) a clear fills every entry with NaN and an index no list
// holds, so an entry read before it is written shows in the results.
const ORCA_POISON_INDEX: u32 = 0xfffffffeu;

fn orca_poison_f32() -> f32 {
    return bitcast<f32>(0x7fc00001u);
}

fn orca_agent_neighbors_clear(list: ptr<function, OrcaAgentNeighbors>) {
    (*list).len = 0u;
    (*list).overflow = 0u;
    if (ORCA_POISON_LISTS) {
        for (var i = 0u; i < ORCA_MAX_AGENT_NEIGHBORS; i++) {
            (*list).items[i] = OrcaNeighborKey(orca_poison_f32(), ORCA_POISON_INDEX);
        }
    }
}

fn orca_obstacle_neighbors_clear(list: ptr<function, OrcaObstacleNeighbors>) {
    (*list).len = 0u;
    (*list).overflow = 0u;
    if (ORCA_POISON_LISTS) {
        for (var i = 0u; i < ORCA_MAX_OBSTACLE_NEIGHBORS; i++) {
            (*list).items[i] = OrcaNeighborKey(orca_poison_f32(), ORCA_POISON_INDEX);
        }
    }
}

fn orca_lines_clear(lines: ptr<function, OrcaLines>) {
    (*lines).len = 0u;
    (*lines).num_obstacle_lines = 0u;
    (*lines).overflow = 0u;
    if (ORCA_POISON_LISTS) {
        let nan = vec2<f32>(orca_poison_f32(), orca_poison_f32());
        for (var i = 0u; i < ORCA_MAX_LINES; i++) {
            (*lines).items[i] = OrcaLine(nan, nan);
        }
    }
}

fn orca_lines_push(lines: ptr<function, OrcaLines>, line: OrcaLine) {
    if ((*lines).len < ORCA_MAX_LINES) {
        (*lines).items[(*lines).len] = line;
        (*lines).len = (*lines).len + 1u;
    } else {
        (*lines).overflow = ORCA_OVERFLOW_LINES;
    }
}

fn orca_left_leg(rel: vec2<f32>, leg: f32, r: f32, q: f32) -> vec2<f32> {
    return orca_div_scalar(vec2<f32>(rel.x * leg - rel.y * r, rel.x * r + rel.y * leg), q);
}

fn orca_right_leg(rel: vec2<f32>, leg: f32, r: f32, q: f32) -> vec2<f32> {
    return orca_div_scalar(vec2<f32>(rel.x * leg + rel.y * r, -rel.x * r + rel.y * leg), q);
}

// Rust `already_covered`: do earlier lines cover this edge's velocity obstacle?
fn orca_already_covered(
    lines: ptr<function, OrcaLines>,
    inv_to: f32,
    rel1: vec2<f32>,
    rel2: vec2<f32>,
    r: f32,
) -> bool {
    for (var k = 0u; k < (*lines).len; k = k + 1u) {
        let l = (*lines).items[k];
        if (orca_det(inv_to * rel1 - l.point, l.direction) - inv_to * r >= -ORCA_RVO_EPSILON
            && orca_det(inv_to * rel2 - l.point, l.direction) - inv_to * r >= -ORCA_RVO_EPSILON) {
            return true;
        }
    }
    return false;
}

// Rust `obstacle_line`: the line for edge `o1 -> o2` (`some` false when RVO2 adds none).
struct OrcaMaybeLine {
    some: bool,
    line: OrcaLine,
}

fn orca_no_line() -> OrcaMaybeLine {
    return OrcaMaybeLine(false, OrcaLine(vec2<f32>(0.0, 0.0), vec2<f32>(0.0, 0.0)));
}

fn orca_some_line(point: vec2<f32>, direction: vec2<f32>) -> OrcaMaybeLine {
    return OrcaMaybeLine(true, OrcaLine(point, direction));
}

fn orca_obstacle_line(
    o1_in: OrcaVertex,
    o2_in: OrcaVertex,
    rel1: vec2<f32>,
    rel2: vec2<f32>,
    pos: vec2<f32>,
    vel: vec2<f32>,
    r: f32,
    inv_to: f32,
) -> OrcaMaybeLine {
    var o1 = o1_in;
    var o2 = o2_in;
    let dist_sq1 = orca_abs_sq(rel1);
    let dist_sq2 = orca_abs_sq(rel2);
    let radius_sq = r * r;
    let obstacle_vector = o2.point - o1.point;
    let s = orca_dot(-rel1, obstacle_vector) / orca_abs_sq(obstacle_vector);
    let dist_sq_line = orca_abs_sq(-rel1 - s * obstacle_vector);

    // Current collision with the left vertex, the right vertex or the segment.
    if (s < 0.0 && dist_sq1 <= radius_sq) {
        if (o1.convex != 0u) {
            return orca_some_line(vec2<f32>(0.0, 0.0), orca_normalize(orca_perp_l(rel1)));
        }
        return orca_no_line();
    }
    if (s > 1.0 && dist_sq2 <= radius_sq) {
        let add = o2.convex != 0u && orca_det(rel2, o2.dir) >= 0.0;
        if (add) {
            return orca_some_line(vec2<f32>(0.0, 0.0), orca_normalize(orca_perp_l(rel2)));
        }
        return orca_no_line();
    }
    if (0.0 <= s && s <= 1.0 && dist_sq_line <= radius_sq) {
        return orca_some_line(vec2<f32>(0.0, 0.0), -o1.dir);
    }

    // No collision: legs. Seen obliquely, a single vertex defines both legs.
    var left_dir: vec2<f32>;
    var right_dir: vec2<f32>;
    if (s < 0.0 && dist_sq_line <= radius_sq) {
        if (o1.convex == 0u) {
            return orca_no_line();
        }
        o2 = o1;
        let leg1 = sqrt(dist_sq1 - radius_sq);
        left_dir = orca_left_leg(rel1, leg1, r, dist_sq1);
        right_dir = orca_right_leg(rel1, leg1, r, dist_sq1);
    } else if (s > 1.0 && dist_sq_line <= radius_sq) {
        if (o2.convex == 0u) {
            return orca_no_line();
        }
        o1 = o2;
        let leg2 = sqrt(dist_sq2 - radius_sq);
        left_dir = orca_left_leg(rel2, leg2, r, dist_sq2);
        right_dir = orca_right_leg(rel2, leg2, r, dist_sq2);
    } else {
        if (o1.convex != 0u) {
            let leg1 = sqrt(dist_sq1 - radius_sq);
            left_dir = orca_left_leg(rel1, leg1, r, dist_sq1);
        } else {
            left_dir = -o1.dir;
        }
        if (o2.convex != 0u) {
            let leg2 = sqrt(dist_sq2 - radius_sq);
            right_dir = orca_right_leg(rel2, leg2, r, dist_sq2);
        } else {
            right_dir = o1.dir;
        }
    }

    // Legs that point into the neighbouring edge become "foreign" (left neighbour: prev(o1)).
    var left_foreign = false;
    var right_foreign = false;
    if (o1.convex != 0u && orca_det(left_dir, -o1.prev_dir) >= 0.0) {
        left_dir = -o1.prev_dir;
        left_foreign = true;
    }
    if (o2.convex != 0u && orca_det(right_dir, o2.dir) <= 0.0) {
        right_dir = o2.dir;
        right_foreign = true;
    }

    // Project the current velocity on the truncated velocity obstacle.
    let left_cutoff = inv_to * (o1.point - pos);
    let right_cutoff = inv_to * (o2.point - pos);
    let cutoff_vec = right_cutoff - left_cutoff;
    let same = o1.index == o2.index;
    var t: f32;
    if (same) {
        t = 0.5;
    } else {
        t = orca_dot(vel - left_cutoff, cutoff_vec) / orca_abs_sq(cutoff_vec);
    }
    let t_left = orca_dot(vel - left_cutoff, left_dir);
    let t_right = orca_dot(vel - right_cutoff, right_dir);
    let r_inv_to = r * inv_to;

    if ((t < 0.0 && t_left < 0.0) || (same && t_left < 0.0 && t_right < 0.0)) {
        let unit_w = orca_normalize(vel - left_cutoff);
        return orca_some_line(left_cutoff + r_inv_to * unit_w, vec2<f32>(unit_w.y, -unit_w.x));
    }
    if (t > 1.0 && t_right < 0.0) {
        let unit_w = orca_normalize(vel - right_cutoff);
        return orca_some_line(right_cutoff + r_inv_to * unit_w, vec2<f32>(unit_w.y, -unit_w.x));
    }

    // `t < 0 || t > 1` is false for NaN, as in RVO2.
    var dist_sq_cutoff: f32;
    if (t < 0.0 || t > 1.0 || same) {
        dist_sq_cutoff = math_inf();
    } else {
        dist_sq_cutoff = orca_abs_sq(vel - (left_cutoff + t * cutoff_vec));
    }
    var dist_sq_left: f32;
    if (t_left < 0.0) {
        dist_sq_left = math_inf();
    } else {
        dist_sq_left = orca_abs_sq(vel - (left_cutoff + t_left * left_dir));
    }
    var dist_sq_right: f32;
    if (t_right < 0.0) {
        dist_sq_right = math_inf();
    } else {
        dist_sq_right = orca_abs_sq(vel - (right_cutoff + t_right * right_dir));
    }

    if (dist_sq_cutoff <= dist_sq_left && dist_sq_cutoff <= dist_sq_right) {
        let direction = -o1.dir;
        return orca_some_line(left_cutoff + r_inv_to * orca_perp_l(direction), direction);
    }
    if (dist_sq_left <= dist_sq_right) {
        if (left_foreign) {
            return orca_no_line();
        }
        return orca_some_line(left_cutoff + r_inv_to * orca_perp_l(left_dir), left_dir);
    }
    if (right_foreign) {
        return orca_no_line();
    }
    let direction = -right_dir;
    return orca_some_line(right_cutoff + r_inv_to * orca_perp_l(direction), direction);
}

// One iteration of Rust `push_obstacle_lines`' loop: the selected edge from `o1` to `o2` (its
// next vertex). Call it for the obstacle neighbours in order, before any agent line, then set
// `num_obstacle_lines = len`.
fn orca_push_obstacle_line(
    agent: OrcaAgent,
    o1: OrcaVertex,
    o2: OrcaVertex,
    lines: ptr<function, OrcaLines>,
) {
    let inv_to = 1.0 / agent.time_horizon_obst;
    let pos = agent.pos;
    let vel = agent.vel;
    let r = agent.radius;
    let rel1 = o1.point - pos;
    let rel2 = o2.point - pos;
    if (orca_already_covered(lines, inv_to, rel1, rel2, r)) {
        return;
    }
    let line = orca_obstacle_line(o1, o2, rel1, rel2, pos, vel, r, inv_to);
    if (line.some) {
        orca_lines_push(lines, line.line);
    }
}

// Rust `agent_line`: RVO2's reciprocal ORCA line against one neighbour.
fn orca_agent_line(
    pos: vec2<f32>,
    vel: vec2<f32>,
    radius: f32,
    other: OrcaNeighbor,
    inv_t: f32,
    time_step: f32,
) -> OrcaLine {
    let rel_pos = other.pos - pos;
    let rel_vel = vel - other.vel;
    let dist_sq = orca_abs_sq(rel_pos);
    let combined_radius = radius + other.radius;
    let combined_radius_sq = combined_radius * combined_radius;

    var direction: vec2<f32>;
    var u: vec2<f32>;
    if (dist_sq > combined_radius_sq) {
        // No collision. w: from the cut-off centre to the relative velocity.
        let w = rel_vel - inv_t * rel_pos;
        let w_length_sq = orca_abs_sq(w);
        let dot1 = orca_dot(w, rel_pos);
        if (dot1 < 0.0 && dot1 * dot1 > combined_radius_sq * w_length_sq) {
            // Project on the cut-off circle.
            let w_length = sqrt(w_length_sq);
            let unit_w = orca_div_scalar(w, w_length);
            direction = vec2<f32>(unit_w.y, -unit_w.x);
            u = (combined_radius * inv_t - w_length) * unit_w;
        } else {
            // Project on a leg; det == 0 (symmetric set-ups) takes the right leg.
            let leg = sqrt(dist_sq - combined_radius_sq);
            if (orca_det(rel_pos, w) > 0.0) {
                direction = orca_left_leg(rel_pos, leg, combined_radius, dist_sq);
            } else {
                direction = -orca_right_leg(rel_pos, leg, combined_radius, dist_sq);
            }
            let dot2 = orca_dot(rel_vel, direction);
            u = dot2 * direction - rel_vel;
        }
    } else {
        // Collision: project on the cut-off circle of time `time_step`.
        let inv_time_step = 1.0 / time_step;
        let w = rel_vel - inv_time_step * rel_pos;
        let w_length = orca_abs(w);
        let unit_w = orca_div_scalar(w, w_length);
        direction = vec2<f32>(unit_w.y, -unit_w.x);
        u = (combined_radius * inv_time_step - w_length) * unit_w;
    }
    return OrcaLine(vel + 0.5 * u, direction);
}

// One iteration of Rust `push_agent_lines`' loop: the line against the next selected neighbour.
fn orca_push_agent_line(
    agent: OrcaAgent,
    other: OrcaNeighbor,
    time_step: f32,
    lines: ptr<function, OrcaLines>,
) {
    let inv_t = 1.0 / agent.time_horizon;
    orca_lines_push(lines, orca_agent_line(agent.pos, agent.vel, agent.radius, other, inv_t, time_step));
}

// ---- lp.rs --------------------------------------------------------------------------------------

// Rust `lp1`'s `Option<Vec2>`.
struct OrcaLp1 {
    ok: bool,
    result: vec2<f32>,
}

// Rust `lp2`'s `(fail, result)`.
struct OrcaLp2 {
    fail: u32,
    result: vec2<f32>,
}

fn orca_lp1(
    lines: ptr<function, OrcaLines>,
    line_no: u32,
    radius: f32,
    opt: vec2<f32>,
    direction_opt: bool,
) -> OrcaLp1 {
    let fail = OrcaLp1(false, vec2<f32>(0.0, 0.0));
    let line = (*lines).items[line_no];
    let line_dot = orca_dot(line.point, line.direction);
    // Rust: `discriminant = dot * dot + radius * radius - |point|²; if discriminant < 0 {..}`.
    // NIR reassociates `(a·b + c·d) + e` (e not a product, the inner sum used once) into
    // `(a·b + e) + c·d` "for FMA-friendly code", which rounds differently. So the inner sum gets a
    // second use: the test `dd_rr < point_sq`, which equals `discriminant < 0` for every input
    // (`x - y < 0` iff `x < y` in IEEE arithmetic without flushing, NaN and infinities included).
    let dd_rr = line_dot * line_dot + radius * radius;
    let point_sq = orca_abs_sq(line.point);
    if (dd_rr < point_sq) {
        // The speed disc fully invalidates line `line_no`.
        return fail;
    }
    let discriminant = dd_rr - point_sq;
    let sqrt_disc = sqrt(discriminant);
    var t_left = -line_dot - sqrt_disc;
    var t_right = -line_dot + sqrt_disc;

    for (var k = 0u; k < line_no; k = k + 1u) {
        let other = (*lines).items[k];
        let denominator = orca_det(line.direction, other.direction);
        let numerator = orca_det(other.direction, line.point - other.point);
        if (abs(denominator) <= ORCA_RVO_EPSILON) {
            // (Almost) parallel lines.
            if (numerator < 0.0) {
                return fail;
            }
            continue;
        }
        let t = numerator / denominator;
        // `std::min`/`std::max` written out, as in the Rust.
        if (denominator >= 0.0) {
            if (t < t_right) {
                t_right = t;
            }
        } else if (t_left < t) {
            t_left = t;
        }
        if (t_left > t_right) {
            return fail;
        }
    }

    var t: f32;
    if (direction_opt) {
        if (orca_dot(opt, line.direction) > 0.0) {
            t = t_right;
        } else {
            t = t_left;
        }
    } else {
        let t_opt = orca_dot(line.direction, opt - line.point);
        if (t_opt < t_left) {
            t = t_left;
        } else if (t_opt > t_right) {
            t = t_right;
        } else {
            t = t_opt;
        }
    }
    return OrcaLp1(true, line.point + t * line.direction);
}

fn orca_lp2(lines: ptr<function, OrcaLines>, radius: f32, opt: vec2<f32>, direction_opt: bool) -> OrcaLp2 {
    var result: vec2<f32>;
    if (direction_opt) {
        // opt is a unit vector here.
        result = opt * radius;
    } else if (orca_abs_sq(opt) > radius * radius) {
        result = orca_normalize(opt) * radius;
    } else {
        result = opt;
    }
    for (var i = 0u; i < (*lines).len; i = i + 1u) {
        let li = (*lines).items[i];
        if (orca_det(li.direction, li.point - result) > 0.0) {
            // `result` violates line i: re-optimise on it.
            let r = orca_lp1(lines, i, radius, opt, direction_opt);
            if (r.ok) {
                result = r.result;
            } else {
                return OrcaLp2(i, result);
            }
        }
    }
    return OrcaLp2((*lines).len, result);
}

// What `orca_lp3` returns: the velocity (m/s) and its working memory's ORCA_OVERFLOW_* bits.
struct OrcaLp3 {
    result: vec2<f32>,
    overflow: u32,
}

// RVO2's `linearProgram3`. Its working memory (Rust's `proj`, the projected lines) is a variable
// of its own, not the caller's: where the lists are zeroed (WGSL compiled by wgpu, not the
// backend's own SPIR-V: src/backend/gpu/spirv.rs), declared here it is zeroed only by the rare
// calls that need LP3, not by every ORCA call (issue 19: 3,088 bytes a call at ORCA_MAX_LINES =
// 192).
fn orca_lp3(
    lines: ptr<function, OrcaLines>,
    num_obst_lines: u32,
    begin_line: u32,
    radius: f32,
    result_in: vec2<f32>,
) -> OrcaLp3 {
    var proj: OrcaLines;
    orca_lines_clear(&proj);
    var result = result_in;
    var distance = 0.0;
    for (var i = begin_line; i < (*lines).len; i = i + 1u) {
        let li = (*lines).items[i];
        if (orca_det(li.direction, li.point - result) > distance) {
            // `result` violates line i by more than the current maximum.
            orca_lines_clear(&proj);
            for (var k = 0u; k < num_obst_lines; k = k + 1u) {
                orca_lines_push(&proj, (*lines).items[k]);
            }
            // RVO2 loops j from numObstLines to i: empty when LP2 failed on an obstacle line.
            for (var j = min(num_obst_lines, i); j < i; j = j + 1u) {
                let lj = (*lines).items[j];
                let determinant = orca_det(li.direction, lj.direction);
                var point: vec2<f32>;
                if (abs(determinant) <= ORCA_RVO_EPSILON) {
                    // Parallel lines.
                    if (orca_dot(li.direction, lj.direction) > 0.0) {
                        // Same direction: nothing to add.
                        continue;
                    }
                    // Opposite directions: the mid-line.
                    point = 0.5 * (li.point + lj.point);
                } else {
                    point = li.point + (orca_det(lj.direction, li.point - lj.point) / determinant) * li.direction;
                }
                orca_lines_push(&proj, OrcaLine(point, orca_normalize(lj.direction - li.direction)));
            }
            let opt = vec2<f32>(-li.direction.y, li.direction.x);
            let r = orca_lp2(&proj, radius, opt, true);
            // A failure here is float round-off only: RVO2 keeps the previous result.
            if (r.fail >= proj.len) {
                result = r.result;
            }
            distance = orca_det(li.direction, li.point - result);
        }
    }
    return OrcaLp3(result, proj.overflow);
}

// ---- mod.rs -------------------------------------------------------------------------------------

// Rust `solve` after the lines: LP2 and, if it fails, LP3 (obstacle lines hard).
fn orca_solve(agent: OrcaAgent, lines: ptr<function, OrcaLines>) -> OrcaResult {
    let r2 = orca_lp2(lines, agent.max_speed, agent.pref_vel, false);
    if (r2.fail >= (*lines).len) {
        return OrcaResult(r2.result, 0u, (*lines).overflow);
    }
    let r3 = orca_lp3(lines, (*lines).num_obstacle_lines, r2.fail, agent.max_speed, r2.result);
    return OrcaResult(r3.result, 1u, (*lines).overflow | r3.overflow);
}
