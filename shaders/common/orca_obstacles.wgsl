// requires: common/orca.wgsl
// requires: common/world.wgsl
//
// Twin of src/systems/orca_obstacles.rs (`for_each_polygon`, `rebuild_if_dirty`, `store`,
// `box_distance_sq`) and of RVO2's `addObstacle` + `processObstacles` in
// src/orca/obstacle_build.rs (`add_polygon`, `choose_split` with RVO2's early exit,
// `split_edge`, `build_node`). Library file (no entry point), for stage shaders (it reads the
// prelude's `sf`/`su`/`params`). Same operations in the same order as the Rust files; change
// them together. The vector helpers are common/orca.wgsl's (`orca_left_of`, `orca_det`,
// `orca_normalize`, ...), which mirror src/orca/vector.rs.
//
// Public functions (kept stable for the stages that build on them):
// Public functions (kept stable for the stages that build on them):
// * `orca_obstacles_rebuild_if_dirty(e: u32)`: Rust `rebuild_if_dirty`: when `obstacles_dirty`
//   is set, every polygon of environment e processed into the `ov_*` columns and
//   `n_obstacle_vertices`, and the flag cleared.
// * `orca_obstacles_raw_count(e: u32) -> u32` and `orca_obstacles_polygon(e: u32, k: u32) ->
//   OrcaObstaclePolygon`: Rust `for_each_polygon` as an indexed walk. For k in
//   0..orca_obstacles_raw_count(e), in order, the polygons whose `present` is true are those
//   `for_each_polygon` visits, in its order (0.1.1's: tables, free laptops, plants, walls, laptop
//   users, standing groups); `seen_as_rect` says whether a field of view tests it as `rect` (a
//   table, laptop or wall) or as `disc` (a plant, laptop use or standing group), `v` holds its
//   four corners counter-clockwise.
// * `orca_obstacles_list(e: u32) -> u32`: environment e's polygon list, emptied (a handle: the
//   list's first word in `scratch`); `orca_obstacles_push(list: u32, v: array<vec2<f32>, 4>)`
//   appends one polygon, `orca_obstacles_list_len(list)` and `orca_obstacles_list_overflow(list)`
//   read it.
// * `orca_obstacles_process(e: u32)`: Rust `process_obstacles` of environment e's polygon list
//   into its processed set: `len` vertices (input vertices, then split vertices in RVO2's order)
//   with `point`, `dir`, `next`, `prev`, `convex` (the `ov_*` layout, local indices), and
//   `overflow` (0: the CPU's result; see below). A walker with a restricted field of view (Rust
//   `with_visible`) pushes the polygons it sees and processes them with this.
// * `orca_obstacles_set(e: u32) -> u32`: the handle of that set, read with
//   `orca_obstacles_set_len(set)`, `orca_obstacles_set_overflow(set)`,
//   `orca_obstacles_set_point(set, i)`, `orca_obstacles_set_next(set, i)` and
//   `orca_obstacles_set_vertex(set, i) -> OrcaVertex` (what an ORCA obstacle line reads of vertex
//   i: common/orca.wgsl's `orca_obstacle_neighbor_candidate` takes `point[i]` and
//   `point[next[i]]`, `orca_push_obstacle_line` two vertices).
// * `orca_obstacles_box_distance_sq(pos: vec2<f32>, v: array<vec2<f32>, 4>) -> f32`: Rust
//   `box_distance_sq` (squared distance to the polygon's bounding box, 0 inside).
//
// Working memory. The polygon list, the processed set and the tree build's stack live in
// environment e's region of the `scratch` buffer (binding 8: `batch.s_scratch` words per
// environment, laid out by Rust `backend::wgsl::ObstacleScratch`; f32 values as their bits), not
// in function-scope arrays: llvmpipe's compile time grows quickly with a shader's private memory
// (a few minutes for each of these shaders at 512 vertices), and arrays sized by a capacity made
// every capacity class a shader of its own; with the scratch buffer one compiled shader serves
// every config. One invocation steps one environment and uses one list and one set at a time
// (the environment's rebuild, or one walker's visible subset), so one region per environment
// suffices; nothing in it outlives the call that fills it. (A regrouping's slot permutations
// pass their old slots through the same region, in `main`, before the rebuild's dispatch:
// backend::wgsl::scratch_region_words; the library's own part is `batch.obstacle_words`.) The
// rebuild entry point of hardware adapters (`rebuild_in_workgroups`) takes this file with the
// region moved into a workgroup array instead (backend::wgsl::with_obstacles_in_workgroup): one
// environment at a time per workgroup, its lanes sharing the polygons, each tree node's split
// search and split, and the store (`orca_obstacles_rebuild_on_lanes`, below; no polygon list
// there: each lane adds its polygons to the set).
//
// Capacities and overflow. The processed set holds orca_obstacles_cap() = batch.s_ov_x vertices,
// the per-environment capacity of the `ov_*` columns (Rust `store` asserts the same bound); a
// list holds batch.s_ov_x / 8 polygons (`Caps` gives every polygon room for 8 processed
// vertices: its 4 and as many split vertices, so an environment never has more). The tree build
// keeps its edge lists on an explicit stack: a node's list is popped, split into its left and
// right lists, and those are pushed (right first), so the left subtree is built completely
// before the right one, as in the recursive Rust. The lists on the stack hold distinct vertex ids
// (each edge goes to one side; a split edge's two pieces have two ids), so the stack never holds
// more than `len` <= batch.s_ov_x ids or lists: its arrays of batch.s_ov_x cannot overflow unless
// the vertex set does. Where the processed set is larger than batch.s_ov_x (overlapping
// obstacles split each other's edges many times over: a state loaded or edited so, never a
// generated scene), or a polygon is degenerate or non-finite (which Rust's `validate_polygons`
// rejects, and no state holds), the set gets a non-zero `overflow`
// (ORCA_OVERFLOW_OBSTACLE_VERTICES, ORCA_OBSTACLES_INVALID) and processing stops; a caller of
// `orca_obstacles_process` must treat it as an error (an ORCA result that ORs it in is NaN by
// common/orca.wgsl's convention). `orca_obstacles_rebuild_if_dirty` then poisons the columns:
// every one of the batch.s_ov_x vertices gets NaN coordinates and directions, in one ring
// (`n_obstacle_vertices` = batch.s_ov_x), and `obstacles_dirty` is left at
// ORCA_OBSTACLES_FAILED (the prelude's, Rust's `OBSTACLES_FAILED`) instead of 0, so the host
// can see it: the same columns and flag as Rust's `rebuild_if_dirty` leaves for a set too large.
//
// Loop budget on lavapipe: llvmpipe stops every loop of an invocation after 65535 loop iterations
// in total (docs/ARCHITECTURE.md). `choose_split` costs up to n² iterations per node (fewer with
// RVO2's early exit); the shipped configs' rebuilds (tests/suite/step/social_events/gpu.rs and
// formation.rs, stress included) stay within it, but a much larger obstacle set could exceed it
// there.

// Obstacle vertices of one environment (at least 1).
fn orca_obstacles_cap() -> u32 {
    return max(batch.s_ov_x, 1u);
}

// Polygons of one environment (at least 1).
fn orca_obstacles_max_polygons() -> u32 {
    return max(batch.s_ov_x / 8u, 1u);
}
// `overflow` bit of a polygon list the Rust scenario would reject (see the header).
const ORCA_OBSTACLES_INVALID: u32 = 16u;

// One polygon of `for_each_polygon` (see the header).
struct OrcaObstaclePolygon {
    present: bool,
    seen_as_rect: bool,
    rect: Rect,
    disc: Disc,
    v: array<vec2<f32>, 4>,
}

// ---- the working memory (see the header) --------------------------------------------------------

// A polygon list at handle l: [len, overflow, then 8 words a polygon: its 4 corners' x, y].
// A processed set at handle s: [len, overflow, then the columns point.x, point.y, dir.x, dir.y,
// next, prev, convex of orca_obstacles_cap() words each] (Rust `ObstacleSet`'s vertex columns;
// the tree itself is not kept: nothing reads it). The stack at handle k: arena, lens, tmp, of
// orca_obstacles_cap() words each.
const ORCA_OBSTACLES_POINT_X: u32 = 0u;
const ORCA_OBSTACLES_POINT_Y: u32 = 1u;
const ORCA_OBSTACLES_DIR_X: u32 = 2u;
const ORCA_OBSTACLES_DIR_Y: u32 = 3u;
const ORCA_OBSTACLES_NEXT: u32 = 4u;
const ORCA_OBSTACLES_PREV: u32 = 5u;
const ORCA_OBSTACLES_CONVEX: u32 = 6u;
const ORCA_OBSTACLES_ARENA: u32 = 0u;
const ORCA_OBSTACLES_LENS: u32 = 1u;
const ORCA_OBSTACLES_TMP: u32 = 2u;

fn orca_obstacles_region(e: u32) -> u32 {
    return e * batch.s_scratch;
}

fn orca_obstacles_list(e: u32) -> u32 {
    let l = orca_obstacles_region(e) + batch.x_obstacle_list;
    scratch[l] = 0u;
    scratch[l + 1u] = 0u;
    return l;
}

fn orca_obstacles_list_len(l: u32) -> u32 {
    return scratch[l];
}

fn orca_obstacles_list_overflow(l: u32) -> u32 {
    return scratch[l + 1u];
}

// Corner k of polygon p of list l.
fn orca_obstacles_list_corner(l: u32, p: u32, k: u32) -> vec2<f32> {
    let w = l + 2u + p * 8u + k * 2u;
    return vec2<f32>(bitcast<f32>(scratch[w]), bitcast<f32>(scratch[w + 1u]));
}

fn orca_obstacles_list_polygon(l: u32, p: u32) -> array<vec2<f32>, 4> {
    return array<vec2<f32>, 4>(
        orca_obstacles_list_corner(l, p, 0u),
        orca_obstacles_list_corner(l, p, 1u),
        orca_obstacles_list_corner(l, p, 2u),
        orca_obstacles_list_corner(l, p, 3u),
    );
}

fn orca_obstacles_set(e: u32) -> u32 {
    return orca_obstacles_region(e) + batch.x_obstacle_set;
}

fn orca_obstacles_set_len(s: u32) -> u32 {
    return scratch[s];
}

fn orca_obstacles_set_overflow(s: u32) -> u32 {
    return scratch[s + 1u];
}

// The word of column `column` of vertex i of set s.
fn orca_obstacles_at(s: u32, column: u32, i: u32) -> u32 {
    return s + 2u + column * orca_obstacles_cap() + i;
}

fn orca_obstacles_set_point(s: u32, i: u32) -> vec2<f32> {
    return vec2<f32>(
        bitcast<f32>(scratch[orca_obstacles_at(s, ORCA_OBSTACLES_POINT_X, i)]),
        bitcast<f32>(scratch[orca_obstacles_at(s, ORCA_OBSTACLES_POINT_Y, i)]),
    );
}

fn orca_obstacles_set_dir(s: u32, i: u32) -> vec2<f32> {
    return vec2<f32>(
        bitcast<f32>(scratch[orca_obstacles_at(s, ORCA_OBSTACLES_DIR_X, i)]),
        bitcast<f32>(scratch[orca_obstacles_at(s, ORCA_OBSTACLES_DIR_Y, i)]),
    );
}

fn orca_obstacles_set_next(s: u32, i: u32) -> u32 {
    return scratch[orca_obstacles_at(s, ORCA_OBSTACLES_NEXT, i)];
}

fn orca_obstacles_set_prev(s: u32, i: u32) -> u32 {
    return scratch[orca_obstacles_at(s, ORCA_OBSTACLES_PREV, i)];
}

fn orca_obstacles_set_convex(s: u32, i: u32) -> u32 {
    return scratch[orca_obstacles_at(s, ORCA_OBSTACLES_CONVEX, i)];
}

// Word i of stack array `which` (ORCA_OBSTACLES_ARENA, _LENS, _TMP) of environment e.
fn orca_obstacles_stack(e: u32, which: u32, i: u32) -> u32 {
    return orca_obstacles_region(e) + batch.x_obstacle_stack + which * orca_obstacles_cap() + i;
}

// ---- orca_obstacles.rs: the polygons ------------------------------------------------------------

// Rust `corners`: the rectangle's corners in 0.1.1's counter-clockwise order (`Rect::corner`).
fn orca_obstacles_corners(r: Rect) -> array<vec2<f32>, 4> {
    var out: array<vec2<f32>, 4>;
    for (var k = 0u; k < 4u; k++) {
        var lx = r.hl;
        var ly = r.hw;
        if (k == 1u) {
            lx = -r.hl;
        } else if (k == 2u) {
            lx = -r.hl;
            ly = -r.hw;
        } else if (k == 3u) {
            ly = -r.hw;
        }
        let dx = orca_obstacles_keep(lx * r.c - ly * r.s);
        let dy = orca_obstacles_keep(lx * r.s + ly * r.c);
        out[k] = vec2<f32>(r.x + dx, r.y + dy);
    }
    return out;
}

// The identity, opaque to the compiler: Mesa's NIR reassociates `e + (a·b + c·d)` (the inner sum
// used once) into `(e + a·b) + c·d`, which rounds differently from Rust (see common/orca.wgsl's
// header); an inner sum passed through this keeps Rust's order. `params.pad[0]` is always 0 (Rust
// `StepParams::_pad`), which the compiler cannot know.
fn orca_obstacles_keep(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) ^ params.pad[0]);
}

// Rust `square`: the axis-aligned square of half-side h around (x, y), counter-clockwise from
// (+h, +h).
fn orca_obstacles_square(x: f32, y: f32, h: f32) -> array<vec2<f32>, 4> {
    return array<vec2<f32>, 4>(
        vec2<f32>(x + h, y + h),
        vec2<f32>(x - h, y + h),
        vec2<f32>(x - h, y - h),
        vec2<f32>(x + h, y - h),
    );
}

// Rust `perception::laptop_use_disc` for global laptop-user slot u of environment e.
fn orca_obstacles_laptop_use_disc(e: u32, u: u32) -> Disc {
    let h = at_human(e, su[batch.c_lu_human + u]);
    let l = at_laptop(e, su[batch.c_lu_laptop + u]);
    return Disc(
        0.5 * (sf[batch.c_l_x + l] + sf[batch.c_h_x + h]),
        0.5 * (sf[batch.c_l_y + l] + sf[batch.c_h_y + h]),
        0.5 * (params.laptop_width + params.human_laptop_distance),
    );
}

// The number of raw indices of `orca_obstacles_polygon` for environment e.
fn orca_obstacles_raw_count(e: u32) -> u32 {
    return su[batch.c_n_tables + e] + su[batch.c_n_laptops + e] + su[batch.c_n_plants + e] + su[batch.c_n_walls + e]
        + su[batch.c_n_laptop_users + e] + su[batch.c_n_groups + e];
}

fn orca_obstacles_rect_polygon(r: Rect) -> OrcaObstaclePolygon {
    return OrcaObstaclePolygon(true, true, r, Disc(0.0, 0.0, 0.0), orca_obstacles_corners(r));
}

fn orca_obstacles_disc_polygon(d: Disc, v: array<vec2<f32>, 4>) -> OrcaObstaclePolygon {
    return OrcaObstaclePolygon(true, false, Rect(0.0, 0.0, 0.0, 0.0, 0.0, 0.0), d, v);
}

// Raw index k of Rust `for_each_polygon` for environment e (see the header).
fn orca_obstacles_polygon(e: u32, k_in: u32) -> OrcaObstaclePolygon {
    var none: OrcaObstaclePolygon;
    var k = k_in;
    let n_tables = su[batch.c_n_tables + e];
    if (k < n_tables) {
        return orca_obstacles_rect_polygon(world_table_rect(e, k));
    }
    k -= n_tables;
    let n_laptops = su[batch.c_n_laptops + e];
    if (k < n_laptops) {
        if (su[batch.c_l_user + at_laptop(e, k)] == NONE) {
            return orca_obstacles_rect_polygon(world_laptop_rect(e, k));
        }
        return none;
    }
    k -= n_laptops;
    let n_plants = su[batch.c_n_plants + e];
    if (k < n_plants) {
        let i = at_plant(e, k);
        let x = sf[batch.c_p_x + i];
        let y = sf[batch.c_p_y + i];
        let r = params.plant_radius;
        return orca_obstacles_disc_polygon(Disc(x, y, r), orca_obstacles_square(x, y, r));
    }
    k -= n_plants;
    let n_walls = su[batch.c_n_walls + e];
    if (k < n_walls) {
        return orca_obstacles_rect_polygon(world_wall_rect(e, k));
    }
    k -= n_walls;
    let n_users = su[batch.c_n_laptop_users + e];
    if (k < n_users) {
        let u = at_laptop_user(e, k);
        let h = at_human(e, su[batch.c_lu_human + u]);
        return orca_obstacles_disc_polygon(
            orca_obstacles_laptop_use_disc(e, u),
            orca_obstacles_square(sf[batch.c_h_x + h], sf[batch.c_h_y + h], params.laptop_user_half_side),
        );
    }
    k -= n_users;
    let g = at_group(e, k);
    if (k < su[batch.c_n_groups + e] && su[batch.c_g_kind + g] == GROUP_STANDING) {
        // Rust `perception::group_disc`.
        let d = Disc(sf[batch.c_g_x + g], sf[batch.c_g_y + g], params.group_radius);
        return orca_obstacles_disc_polygon(d, orca_obstacles_square(sf[batch.c_g_x + g], sf[batch.c_g_y + g], params.group_radius));
    }
    return none;
}

// Appends polygon `v` to list l; past `orca_obstacles_max_polygons()` it flags the overflow.
fn orca_obstacles_push(l: u32, v: array<vec2<f32>, 4>) {
    let len = scratch[l];
    if (len == orca_obstacles_max_polygons()) {
        scratch[l + 1u] |= ORCA_OVERFLOW_OBSTACLE_VERTICES;
        return;
    }
    for (var k = 0u; k < 4u; k++) {
        let w = l + 2u + len * 8u + k * 2u;
        scratch[w] = bitcast<u32>(v[k].x);
        scratch[w + 1u] = bitcast<u32>(v[k].y);
    }
    scratch[l] = len + 1u;
}

// Rust `box_distance_sq`: squared distance (m²) from `pos` to the bounding box of `v` (0 inside).
fn orca_obstacles_box_distance_sq(pos: vec2<f32>, v: array<vec2<f32>, 4>) -> f32 {
    var lo = v[0];
    var hi = v[0];
    for (var k = 1u; k < 4u; k++) {
        lo = vec2<f32>(min(lo.x, v[k].x), min(lo.y, v[k].y));
        hi = vec2<f32>(max(hi.x, v[k].x), max(hi.y, v[k].y));
    }
    let dx = max(max(lo.x - pos.x, pos.x - hi.x), 0.0);
    let dy = max(max(lo.y - pos.y, pos.y - hi.y), 0.0);
    return dx * dx + dy * dy;
}

// ---- obstacle_build.rs --------------------------------------------------------------------------

// Rust `validate_polygons` for quadrilaterals: true if every vertex is finite and every edge's
// squared length a positive finite f32.
fn orca_obstacles_valid(l: u32) -> bool {
    for (var p = 0u; p < orca_obstacles_list_len(l); p++) {
        if (!orca_obstacles_polygon_valid(orca_obstacles_list_polygon(l, p))) {
            return false;
        }
    }
    return true;
}

// Rust `validate_polygons` of one quadrilateral.
fn orca_obstacles_polygon_valid(v: array<vec2<f32>, 4>) -> bool {
    for (var k = 0u; k < 4u; k++) {
        let a = v[k];
        if (!math_is_finite_bits(a.x) || !math_is_finite_bits(a.y)) {
            return false;
        }
    }
    for (var k = 0u; k < 4u; k++) {
        let a = v[k];
        let b = v[(k + 1u) % 4u];
        let len_sq = orca_abs_sq(b - a);
        if (!(len_sq > 0.0 && math_is_finite_bits(len_sq))) {
            return false;
        }
    }
    return true;
}

// Vertex i of set s: its point, direction, neighbours and convexity.
fn orca_obstacles_write_vertex(s: u32, i: u32, p: vec2<f32>, dir: vec2<f32>, next: u32, prev: u32, convex: u32) {
    scratch[orca_obstacles_at(s, ORCA_OBSTACLES_POINT_X, i)] = bitcast<u32>(p.x);
    scratch[orca_obstacles_at(s, ORCA_OBSTACLES_POINT_Y, i)] = bitcast<u32>(p.y);
    scratch[orca_obstacles_at(s, ORCA_OBSTACLES_DIR_X, i)] = bitcast<u32>(dir.x);
    scratch[orca_obstacles_at(s, ORCA_OBSTACLES_DIR_Y, i)] = bitcast<u32>(dir.y);
    scratch[orca_obstacles_at(s, ORCA_OBSTACLES_NEXT, i)] = next;
    scratch[orca_obstacles_at(s, ORCA_OBSTACLES_PREV, i)] = prev;
    scratch[orca_obstacles_at(s, ORCA_OBSTACLES_CONVEX, i)] = convex;
}

// Rust `ObstacleSet::push_vertex`; false (and the overflow flagged) when the set is full.
fn orca_obstacles_push_vertex(s: u32, p: vec2<f32>, dir: vec2<f32>, next: u32, prev: u32, convex: u32) -> bool {
    let i = scratch[s];
    if (i == orca_obstacles_cap()) {
        scratch[s + 1u] |= ORCA_OVERFLOW_OBSTACLE_VERTICES;
        return false;
    }
    orca_obstacles_write_vertex(s, i, p, dir, next, prev, convex);
    scratch[s] = i + 1u;
    return true;
}

// Corner i of quadrilateral v as Rust `add_polygon` links it: its direction, and 1 when convex.
struct OrcaObstacleCorner {
    dir: vec2<f32>,
    convex: u32,
}

fn orca_obstacles_corner(v: array<vec2<f32>, 4>, i: u32) -> OrcaObstacleCorner {
    let p = v[i];
    let p_prev = v[(i + 3u) % 4u];
    let p_next = v[(i + 1u) % 4u];
    var convex = 0u;
    if (orca_left_of(p_prev, p, p_next) >= 0.0) {
        convex = 1u;
    }
    return OrcaObstacleCorner(orca_normalize(p_next - p), convex);
}

// Rust `add_polygon` (RVO2's `addObstacle`) for one quadrilateral.
fn orca_obstacles_add_polygon(s: u32, v: array<vec2<f32>, 4>) {
    let first = scratch[s];
    for (var i = 0u; i < 4u; i++) {
        let c = orca_obstacles_corner(v, i);
        if (!orca_obstacles_push_vertex(s, v[i], c.dir, first + (i + 1u) % 4u, first + (i + 3u) % 4u, c.convex)) {
            return;
        }
    }
}

// Rust `classify`: 0 left, 1 right, 2 both.
fn orca_obstacles_classify(s1: f32, s2: f32) -> u32 {
    if (s1 >= -ORCA_RVO_EPSILON && s2 >= -ORCA_RVO_EPSILON) {
        return 0u;
    } else if (s1 <= ORCA_RVO_EPSILON && s2 <= ORCA_RVO_EPSILON) {
        return 1u;
    }
    return 2u;
}

// Rust `edge_sides`: edge j1 against the line of edge i1.
fn orca_obstacles_edge_sides(s: u32, i1: u32, j1: u32) -> vec2<f32> {
    let a = orca_obstacles_set_point(s, i1);
    let b = orca_obstacles_set_point(s, orca_obstacles_set_next(s, i1));
    let s1 = orca_left_of(a, b, orca_obstacles_set_point(s, j1));
    let s2 = orca_left_of(a, b, orca_obstacles_set_point(s, orca_obstacles_set_next(s, j1)));
    return vec2<f32>(s1, s2);
}

// Lexicographic `(a0, a1) < (b0, b1)` of Rust's tuple keys.
fn orca_obstacles_key_less(a0: u32, a1: u32, b0: u32, b1: u32) -> bool {
    return a0 < b0 || (a0 == b0 && a1 < b1);
}

// RVO2's split candidates `lane`, `lane + lanes`, ... of the list `arena[start..start + n]` of
// environment e: (position, L, R) of the least of them by the key (max(L, R), min(L, R)), the
// first position among equal keys, with RVO2's early exit against the best so far; position NONE
// when the lane has no candidate. A candidate's counts only grow as its loop goes on, so the
// early exit never drops a candidate that would have been chosen, and every candidate's full
// key has max(L, R) < n: the least over all positions is Rust `choose_split`'s choice, whichever
// lanes share the candidates (`orca_obstacles_split_key` orders the lanes' as the loop would).
fn orca_obstacles_split_candidates(e: u32, s: u32, start: u32, n: u32, lane: u32, lanes: u32) -> vec3<u32> {
    var best = NONE;
    var min_left = n;
    var min_right = n;
    for (var i = lane; i < n; i += lanes) {
        let i1 = scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, start + i)];
        let best0 = max(min_left, min_right);
        let best1 = min(min_left, min_right);
        var left = 0u;
        var right = 0u;
        for (var j = 0u; j < n; j++) {
            if (i == j) {
                continue;
            }
            let sides = orca_obstacles_edge_sides(s, i1, scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, start + j)]);
            let side = orca_obstacles_classify(sides.x, sides.y);
            if (side == 0u) {
                left += 1u;
            } else if (side == 1u) {
                right += 1u;
            } else {
                left += 1u;
                right += 1u;
            }
            if (!orca_obstacles_key_less(max(left, right), min(left, right), best0, best1)) {
                break;
            }
        }
        if (orca_obstacles_key_less(max(left, right), min(left, right), best0, best1)) {
            best = i;
            min_left = left;
            min_right = right;
        }
    }
    return vec3<u32>(best, min_left, min_right);
}

// Rust `choose_split` over the list `arena[start..start + n]` of environment e: (position, L, R).
fn orca_obstacles_choose_split(e: u32, s: u32, start: u32, n: u32) -> vec3<u32> {
    return orca_obstacles_split_candidates(e, s, start, n, 0u, 1u);
}

// Rust `split_edge`: splits edge j1 -> next(j1) where it crosses the line of edge i1 -> next(i1);
// the fresh vertex's id, or NONE when the set is full (overflow flagged).
fn orca_obstacles_split_edge(s: u32, i1: u32, j1: u32) -> u32 {
    let fresh = scratch[s];
    if (fresh == orca_obstacles_cap()) {
        scratch[s + 1u] |= ORCA_OVERFLOW_OBSTACLE_VERTICES;
        return NONE;
    }
    orca_obstacles_place_split(s, i1, j1, fresh);
    scratch[s] = fresh + 1u;
    return fresh;
}

// The body of Rust `split_edge` with the fresh vertex's id given: vertex `fresh` where edge
// j1 -> next(j1) crosses the line of edge i1 -> next(i1), linked between them.
fn orca_obstacles_place_split(s: u32, i1: u32, j1: u32, fresh: u32) {
    let j2 = orca_obstacles_set_next(s, j1);
    let a = orca_obstacles_set_point(s, i1);
    let b = orca_obstacles_set_point(s, orca_obstacles_set_next(s, i1));
    let pj1 = orca_obstacles_set_point(s, j1);
    let pj2 = orca_obstacles_set_point(s, j2);
    let t = orca_det(b - a, pj1 - a) / orca_det(b - a, pj1 - pj2);
    let split_point = pj1 + t * (pj2 - pj1);
    orca_obstacles_write_vertex(s, fresh, split_point, orca_obstacles_set_dir(s, j1), j2, j1, 1u);
    scratch[orca_obstacles_at(s, ORCA_OBSTACLES_NEXT, j1)] = fresh;
    scratch[orca_obstacles_at(s, ORCA_OBSTACLES_PREV, j2)] = fresh;
}

// The tree build's stack of edge lists between two nodes: the lists are `arena[..end]`, their
// lengths `lens[..depth]`, the top list last.
struct OrcaObstaclesStack {
    end: u32,
    depth: u32,
}

// The start of Rust `process_obstacles` of environment e's list into its set: the polygons'
// vertices added, and the stack holding the root list of every vertex (none where the list
// overflowed or is invalid, or holds no vertex).
fn orca_obstacles_process_begin(e: u32) -> OrcaObstaclesStack {
    let l = orca_obstacles_region(e) + batch.x_obstacle_list;
    let s = orca_obstacles_set(e);
    scratch[s] = 0u;
    scratch[s + 1u] = orca_obstacles_list_overflow(l);
    if (!orca_obstacles_valid(l)) {
        scratch[s + 1u] |= ORCA_OBSTACLES_INVALID;
    }
    if (scratch[s + 1u] != 0u) {
        return OrcaObstaclesStack(0u, 0u);
    }
    for (var p = 0u; p < orca_obstacles_list_len(l); p++) {
        orca_obstacles_add_polygon(s, orca_obstacles_list_polygon(l, p));
    }
    if (scratch[s + 1u] != 0u) {
        return OrcaObstaclesStack(0u, 0u);
    }
    let n = scratch[s];
    for (var i = 0u; i < n; i++) {
        scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, i)] = i;
    }
    return orca_obstacles_root(e, n);
}

// The stack of a tree build over n vertices whose root list is in place: that list, or nothing.
fn orca_obstacles_root(e: u32, n: u32) -> OrcaObstaclesStack {
    if (n == 0u) {
        return OrcaObstaclesStack(0u, 0u);
    }
    scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_LENS, 0u)] = n;
    return OrcaObstaclesStack(n, 1u);
}

// The top list of the stack, popped: (start, len) in the arena, len 0 when the stack is empty.
// The list's words stay where they are until the node's children are pushed.
fn orca_obstacles_pop(e: u32, stack: ptr<function, OrcaObstaclesStack>) -> vec2<u32> {
    if ((*stack).depth == 0u) {
        return vec2<u32>(0u, 0u);
    }
    (*stack).depth -= 1u;
    let len = scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_LENS, (*stack).depth)];
    let start = (*stack).end - len;
    (*stack).end = start;
    return vec2<u32>(start, len);
}

// Rust `build_node` of the popped list `node` (start, len) split at `chosen` (position, L, R:
// `orca_obstacles_choose_split`): the edges crossing the split edge's line split, the left and
// right lists pushed (right first, so that the left subtree is built completely before the right
// one, as in the recursive Rust). False where the set overflowed: the build stops.
fn orca_obstacles_split_node(e: u32, s: u32, node: vec2<u32>, chosen: vec3<u32>, stack: ptr<function, OrcaObstaclesStack>) -> bool {
    let start = node.x;
    let len = node.y;
    let split = chosen.x;
    let n_left = chosen.y;
    let n_right = chosen.z;
    let i1 = scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, start + split)];
    // Child lists into `tmp`: left at 0.., right at n_left...
    var lc = 0u;
    var rc = 0u;
    for (var j = 0u; j < len; j++) {
        if (j == split) {
            continue;
        }
        let j1 = scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, start + j)];
        let sides = orca_obstacles_edge_sides(s, i1, j1);
        let side = orca_obstacles_classify(sides.x, sides.y);
        var to_left = NONE;
        var to_right = NONE;
        if (side == 0u) {
            to_left = j1;
        } else if (side == 1u) {
            to_right = j1;
        } else {
            let fresh = orca_obstacles_split_edge(s, i1, j1);
            if (fresh == NONE) {
                return false;
            }
            if (sides.x > 0.0) {
                to_left = j1;
                to_right = fresh;
            } else {
                to_left = fresh;
                to_right = j1;
            }
        }
        if (to_left != NONE) {
            scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_TMP, lc)] = to_left;
            lc += 1u;
        }
        if (to_right != NONE) {
            scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_TMP, n_left + rc)] = to_right;
            rc += 1u;
        }
    }
    // Cannot overflow (see the header); checked all the same.
    if (lc != n_left || rc != n_right || start + n_left + n_right > orca_obstacles_cap()) {
        scratch[s + 1u] |= ORCA_OVERFLOW_OBSTACLE_VERTICES;
        return false;
    }
    for (var k = 0u; k < n_right; k++) {
        scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, (*stack).end + k)] =
            scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_TMP, n_left + k)];
    }
    for (var k = 0u; k < n_left; k++) {
        scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, (*stack).end + n_right + k)] =
            scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_TMP, k)];
    }
    orca_obstacles_push_children(e, n_left, n_right, stack);
    return true;
}

// The children of the node just popped, in the arena from the stack's end (the right list, then
// the left), pushed: right first, so that the left subtree is built first. Empty lists are not
// pushed.
fn orca_obstacles_push_children(e: u32, n_left: u32, n_right: u32, stack: ptr<function, OrcaObstaclesStack>) {
    if (n_right > 0u) {
        (*stack).end += n_right;
        scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_LENS, (*stack).depth)] = n_right;
        (*stack).depth += 1u;
    }
    if (n_left > 0u) {
        (*stack).end += n_left;
        scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_LENS, (*stack).depth)] = n_left;
        (*stack).depth += 1u;
    }
}

// Rust `process_obstacles` of environment e's list into its set (see the header): `build_node`
// from the root list of every vertex, with an explicit stack of edge lists.
fn orca_obstacles_process(e: u32) {
    let s = orca_obstacles_set(e);
    var stack = orca_obstacles_process_begin(e);
    loop {
        let node = orca_obstacles_pop(e, &stack);
        if (node.y == 0u) {
            break;
        }
        let chosen = orca_obstacles_choose_split(e, s, node.x, node.y);
        if (!orca_obstacles_split_node(e, s, node, chosen, &stack)) {
            break;
        }
    }
}

// What `orca_obstacle_line` reads of vertex i of a processed set.
fn orca_obstacles_set_vertex(s: u32, i: u32) -> OrcaVertex {
    return orca_vertex(
        i,
        orca_obstacles_set_point(s, i),
        orca_obstacles_set_dir(s, i),
        orca_obstacles_set_dir(s, orca_obstacles_set_prev(s, i)),
        orca_obstacles_set_convex(s, i),
    );
}

// ---- orca_obstacles.rs: the environment's set ---------------------------------------------------

// Every polygon of `for_each_polygon` for environment e into list l.
fn orca_obstacles_gather(e: u32, l: u32) {
    let raw = orca_obstacles_raw_count(e);
    for (var k = 0u; k < raw; k++) {
        let poly = orca_obstacles_polygon(e, k);
        if (poly.present) {
            orca_obstacles_push(l, poly.v);
        }
    }
}

// Rust `store` of environment e's processed set (a set with an overflow poisons the columns
// instead; see the header).
fn orca_obstacles_store(e: u32) {
    let old = su[batch.c_n_obstacle_vertices + e];
    orca_obstacles_store_part(e, old, 0u, 1u);
    su[batch.c_n_obstacle_vertices + e] = orca_obstacles_stored_count(orca_obstacles_set(e));
}

// The `n_obstacle_vertices` that storing set s leaves.
fn orca_obstacles_stored_count(s: u32) -> u32 {
    if (orca_obstacles_set_overflow(s) != 0u) {
        return batch.s_ov_x;
    }
    return orca_obstacles_set_len(s);
}

// The vertex slots `first`, `first + step`, ... of Rust `store` of environment e's processed
// set, whose `n_obstacle_vertices` was `old` before (not written here).
fn orca_obstacles_store_part(e: u32, old: u32, first: u32, step: u32) {
    let s = orca_obstacles_set(e);
    if (orca_obstacles_set_overflow(s) != 0u) {
        for (var k = first; k < batch.s_ov_x; k += step) {
            let i = at_obstacle_vertex(e, k);
            sf[batch.c_ov_x + i] = math_nan();
            sf[batch.c_ov_y + i] = math_nan();
            sf[batch.c_ov_dir_x + i] = math_nan();
            sf[batch.c_ov_dir_y + i] = math_nan();
            su[batch.c_ov_next + i] = (k + 1u) % orca_obstacles_cap();
            su[batch.c_ov_prev + i] = (k + orca_obstacles_cap() - 1u) % orca_obstacles_cap();
            su[batch.c_ov_convex + i] = 1u;
        }
        return;
    }
    let n = orca_obstacles_set_len(s);
    for (var k = first; k < max(n, min(old, batch.s_ov_x)); k += step) {
        let i = at_obstacle_vertex(e, k);
        if (k >= n) {
            // A smaller set than before: its old tail becomes unused slots, which hold zeros.
            sf[batch.c_ov_x + i] = 0.0;
            sf[batch.c_ov_y + i] = 0.0;
            sf[batch.c_ov_dir_x + i] = 0.0;
            sf[batch.c_ov_dir_y + i] = 0.0;
            su[batch.c_ov_next + i] = 0u;
            su[batch.c_ov_prev + i] = 0u;
            su[batch.c_ov_convex + i] = 0u;
            continue;
        }
        let p = orca_obstacles_set_point(s, k);
        let d = orca_obstacles_set_dir(s, k);
        sf[batch.c_ov_x + i] = p.x;
        sf[batch.c_ov_y + i] = p.y;
        sf[batch.c_ov_dir_x + i] = d.x;
        sf[batch.c_ov_dir_y + i] = d.y;
        su[batch.c_ov_next + i] = orca_obstacles_set_next(s, k);
        su[batch.c_ov_prev + i] = orca_obstacles_set_prev(s, k);
        su[batch.c_ov_convex + i] = orca_obstacles_set_convex(s, k);
    }
}

// With ORCA_POISON_LISTS (a test's: `GpuPaths::poison_orca_lists`), every word of environment
// e's working memory made one no list, set or stack holds, so that a word read before it is
// written shows in the results (the working memory is not zeroed: backend::gpu::spirv).
fn orca_obstacles_poison_region(e: u32) {
    if (!ORCA_POISON_LISTS) {
        return;
    }
    let r = orca_obstacles_region(e);
    for (var k = 0u; k < batch.obstacle_words; k++) {
        scratch[r + k] = 0xffffffffu;
    }
}

// Rust `rebuild_if_dirty` (see the header).
fn orca_obstacles_rebuild_if_dirty(e: u32) {
    if (su[batch.c_obstacles_dirty + e] == 0u) {
        return;
    }
    orca_obstacles_poison_region(e);
    orca_obstacles_gather(e, orca_obstacles_list(e));
    orca_obstacles_process(e);
    orca_obstacles_finish(e);
}

// The end of a rebuild of environment e: its processed set stored, its flag cleared (or left
// at ORCA_OBSTACLES_FAILED where the set overflowed).
fn orca_obstacles_finish(e: u32) {
    orca_obstacles_store(e);
    orca_obstacles_clear_flag(e);
}

// Environment e's `obstacles_dirty` once its set is stored: 0, or ORCA_OBSTACLES_FAILED where
// the set overflowed.
fn orca_obstacles_clear_flag(e: u32) {
    if (orca_obstacles_set_overflow(orca_obstacles_set(e)) != 0u) {
        su[batch.c_obstacles_dirty + e] = ORCA_OBSTACLES_FAILED;
    } else {
        su[batch.c_obstacles_dirty + e] = 0u;
    }
}

// ---- a rebuild on a workgroup's lanes -----------------------------------------------------------

// What a rebuild entry's target says besides an environment (src/backend/wgsl/rebuild.rs,
// `rebuild_entries`): this entry has nothing to rebuild, but later ones may (NONE: no later one).
const ORCA_OBSTACLES_SKIP: u32 = 0xfffffffeu;
// ORCA_OBSTACLES_MASK_WORDS, words of each side's mask of a node's edges (`orca_obstacles_left`,
// `orca_obstacles_right`): a bit an edge, for lists of up to 32 times as many edges. The prelude
// declares it from Rust's `REBUILD_MASK_WORDS` (src/backend/wgsl/rebuild.rs), which sizes the
// workgroup memory a rebuild takes; an obstacle region that fits workgroup memory
// (`OBSTACLES_IN_WORKGROUP_WORDS`) has fewer vertices than that, and a longer list would stop its
// rebuild as an overflow.
// Most lanes that share the edges one split candidate counts (`orca_obstacles_choose_on_lanes`).
const ORCA_OBSTACLES_LANES_PER_CANDIDATE: u32 = 8u;

// The workgroup's rebuild in hand: (what it rebuilds, whether its obstacles are dirty).
var<workgroup> orca_obstacles_turn: vec2<u32>;
// The node being split: (start, len) in the arena, len 0 once the tree is built; before the
// tree, (the polygons `for_each_polygon` walks, present or not, the environment's stored vertex
// count before the rebuild, which lane 0 overwrites at its end).
var<workgroup> orca_obstacles_node: vec2<u32>;
// The least split key among the node's candidates (`orca_obstacles_split_key`); before the
// tree, what the polygons' adds found wrong (ORCA_OBSTACLES_TOO_MANY, _DEGENERATE).
var<workgroup> orca_obstacles_best: atomic<u32>;
// Each lane's count of its share of a candidate's edges: left | right << 16.
var<workgroup> orca_obstacles_partial: array<u32, WORKGROUP_SIZE>;
// Bit j of word j / 32: edge j of the node goes to the left (right) of the split edge's line;
// both where the line splits it.
var<workgroup> orca_obstacles_left: array<atomic<u32>, ORCA_OBSTACLES_MASK_WORDS>;
var<workgroup> orca_obstacles_right: array<atomic<u32>, ORCA_OBSTACLES_MASK_WORDS>;

// A split candidate (its position in the node's list, L, R) as one word whose order is Rust
// `choose_split`'s: by max(L, R), then min(L, R), then position, the first winning; the last bit,
// whether L < R, never decides (positions differ). All three are below 1024
// (ORCA_OBSTACLES_MASK_WORDS).
fn orca_obstacles_split_key(pos: u32, left: u32, right: u32) -> u32 {
    return (max(left, right) << 21u) | (min(left, right) << 11u) | (pos << 1u) | select(0u, 1u, left < right);
}

// (position, L, R) of a split key.
fn orca_obstacles_split_of(key: u32) -> vec3<u32> {
    let most = key >> 21u;
    let least = (key >> 11u) & 1023u;
    let pos = (key >> 1u) & 1023u;
    if ((key & 1u) != 0u) {
        return vec3<u32>(pos, least, most);
    }
    return vec3<u32>(pos, most, least);
}

// Split candidate i of the list `arena[start..]` of environment e against the list's edges j0..j1
// (itself left out), counted as Rust `choose_split` counts, whole: left | right << 16.
fn orca_obstacles_count_sides(e: u32, s: u32, start: u32, i: u32, j0: u32, j1: u32) -> u32 {
    let i1 = scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, start + i)];
    var left = 0u;
    var right = 0u;
    for (var j = j0; j < j1; j++) {
        if (j == i) {
            continue;
        }
        let sides = orca_obstacles_edge_sides(s, i1, scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, start + j)]);
        let side = orca_obstacles_classify(sides.x, sides.y);
        if (side != 1u) {
            left += 1u;
        }
        if (side != 0u) {
            right += 1u;
        }
    }
    return left | (right << 16u);
}

// Rust `choose_split` of the node (start, len) of environment e by every lane of the workgroup,
// called by all of them together: the least key into `orca_obstacles_best` (set to the most
// before). A list of up to half a workgroup's edges gives each candidate up to
// ORCA_OBSTACLES_LANES_PER_CANDIDATE lanes (no more than it has edges), each counting a share of
// the other edges, whole; a longer one gives each lane every WORKGROUP_SIZE-th candidate, with
// RVO2's early exit against the lane's best (`orca_obstacles_split_candidates`). Either way each
// candidate that can win is counted whole, and the least key over all of them is RVO2's choice
// (see `orca_obstacles_split_candidates`).
fn orca_obstacles_choose_on_lanes(e: u32, s: u32, node: vec2<u32>, lane: u32) {
    let n = node.y;
    if (2u * n <= WORKGROUP_SIZE) {
        // No more lanes than edges: a share is at least about one edge, its sum a load a lane.
        let per = min(min(WORKGROUP_SIZE / n, ORCA_OBSTACLES_LANES_PER_CANDIDATE), n);
        let i = lane / per;
        let part = lane % per;
        var counts = 0u;
        if (i < n) {
            counts = orca_obstacles_count_sides(e, s, node.x, i, part * n / per, (part + 1u) * n / per);
        }
        orca_obstacles_partial[lane] = counts;
        workgroupBarrier();
        if (i < n && part == 0u) {
            var total = 0u;
            for (var k = 0u; k < per; k++) {
                total += orca_obstacles_partial[lane + k];
            }
            atomicMin(&orca_obstacles_best, orca_obstacles_split_key(i, total & 0xffffu, total >> 16u));
        }
    } else {
        let c = orca_obstacles_split_candidates(e, s, node.x, n, lane, WORKGROUP_SIZE);
        if (c.x != NONE) {
            atomicMin(&orca_obstacles_best, orca_obstacles_split_key(c.x, c.y, c.z));
        }
    }
    workgroupBarrier();
}

// The edges of the node's side masks before edge j: (left, right, split: on both sides).
fn orca_obstacles_sides_before(j: u32) -> vec3<u32> {
    var counts = vec3<u32>(0u, 0u, 0u);
    for (var k = 0u; k <= j / 32u && k < ORCA_OBSTACLES_MASK_WORDS; k++) {
        var left = atomicLoad(&orca_obstacles_left[k]);
        var right = atomicLoad(&orca_obstacles_right[k]);
        if (k == j / 32u) {
            let below = (1u << (j % 32u)) - 1u;
            left &= below;
            right &= below;
        }
        counts += vec3<u32>(countOneBits(left), countOneBits(right), countOneBits(left & right));
    }
    return counts;
}

// Rust `build_node`'s split of the node (start, len) of environment e at `chosen` (position, L,
// R) by every lane of the workgroup, called by all of them together: each lane classifies every
// WORKGROUP_SIZE-th edge into the side masks, then places it by the edges before it on its sides
// (the left list in `tmp` from 0, the right from L), and splits a straddling edge into the vertex
// that the split edges before it give (RVO2's ids: the set's length, one more a split edge in list
// order). Whether the lists have the counts the choice gave and the split vertices fit the set
// (the same on every lane); where not, lane 0 flags an overflow and the build stops.
fn orca_obstacles_split_on_lanes(e: u32, s: u32, node: vec2<u32>, chosen: vec3<u32>, lane: u32) -> bool {
    let start = node.x;
    var n = node.y;
    let i1 = scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, start + chosen.x)];
    let len = orca_obstacles_set_len(s);
    for (var j = lane; j < n; j += WORKGROUP_SIZE) {
        if (j == chosen.x || j >= 32u * ORCA_OBSTACLES_MASK_WORDS) {
            continue;
        }
        let sides = orca_obstacles_edge_sides(s, i1, scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, start + j)]);
        let side = orca_obstacles_classify(sides.x, sides.y);
        let bit = 1u << (j % 32u);
        if (side != 1u) {
            atomicOr(&orca_obstacles_left[j / 32u], bit);
        }
        if (side != 0u) {
            atomicOr(&orca_obstacles_right[j / 32u], bit);
        }
    }
    workgroupBarrier();
    let totals = orca_obstacles_sides_before(min(n, 32u * ORCA_OBSTACLES_MASK_WORDS));
    let cap = orca_obstacles_cap();
    let fits = n <= 32u * ORCA_OBSTACLES_MASK_WORDS && totals.x == chosen.y && totals.y == chosen.z
        && len + totals.z <= cap && start + totals.x + totals.y <= cap;
    if (!fits) {
        if (lane == 0u) {
            scratch[s + 1u] |= ORCA_OVERFLOW_OBSTACLE_VERTICES;
        }
        // No lane leaves early, so that the caller's barriers stay in uniform control flow.
        n = 0u;
    }
    for (var j = lane; j < n; j += WORKGROUP_SIZE) {
        if (j == chosen.x) {
            continue;
        }
        let before = orca_obstacles_sides_before(j);
        let bit = 1u << (j % 32u);
        let goes_left = (atomicLoad(&orca_obstacles_left[j / 32u]) & bit) != 0u;
        let goes_right = (atomicLoad(&orca_obstacles_right[j / 32u]) & bit) != 0u;
        let j1 = scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, start + j)];
        var to_left = j1;
        var to_right = j1;
        if (goes_left && goes_right) {
            // Its first end's side, before the split moves its next vertex.
            let first_left = orca_obstacles_edge_sides(s, i1, j1).x > 0.0;
            let fresh = len + before.z;
            orca_obstacles_place_split(s, i1, j1, fresh);
            if (first_left) {
                to_right = fresh;
            } else {
                to_left = fresh;
            }
        }
        if (goes_left) {
            scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_TMP, before.x)] = to_left;
        }
        if (goes_right) {
            scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_TMP, chosen.y + before.y)] = to_right;
        }
    }
    if (lane == 0u && fits) {
        scratch[s] = len + totals.z;
    }
    return fits;
}

// What `orca_obstacles_add_on_lanes` found wrong (bits of `orca_obstacles_best`): more polygons
// than a list or the set holds (Rust's list, and set, would overflow), a degenerate polygon.
const ORCA_OBSTACLES_TOO_MANY: u32 = 1u;
const ORCA_OBSTACLES_DEGENERATE: u32 = 2u;

// Rust `for_each_polygon`, `validate_polygons` and `add_polygon` of environment e's `raw`
// polygons (`orca_obstacles_raw_count`) by every lane of the workgroup, called by all of them
// together: in runs of 32 × ORCA_OBSTACLES_MASK_WORDS, each lane marks every WORKGROUP_SIZE-th
// polygon present in the left mask, then adds a present one's vertices where the present
// polygons before it put them (the list's order: the vertices of the p-th from 4p, the root
// list's entries with them), and flags in `orca_obstacles_best` (0 before) what Rust would
// reject. The polygons present. No list is kept: its polygons go straight into the set.
fn orca_obstacles_add_on_lanes(e: u32, s: u32, raw: u32, lane: u32) -> u32 {
    let run = 32u * ORCA_OBSTACLES_MASK_WORDS;
    var present = 0u;
    for (var k0 = 0u; k0 < raw; k0 += run) {
        if (lane < ORCA_OBSTACLES_MASK_WORDS) {
            atomicStore(&orca_obstacles_left[lane], 0u);
        }
        workgroupBarrier();
        let end = min(raw, k0 + run);
        for (var k = k0 + lane; k < end; k += WORKGROUP_SIZE) {
            if (orca_obstacles_polygon(e, k).present) {
                atomicOr(&orca_obstacles_left[(k - k0) / 32u], 1u << ((k - k0) % 32u));
            }
        }
        workgroupBarrier();
        for (var k = k0 + lane; k < end; k += WORKGROUP_SIZE) {
            let poly = orca_obstacles_polygon(e, k);
            if (!poly.present) {
                continue;
            }
            let p = present + orca_obstacles_sides_before(k - k0).x;
            if (p >= orca_obstacles_max_polygons() || 4u * p + 4u > orca_obstacles_cap()) {
                atomicOr(&orca_obstacles_best, ORCA_OBSTACLES_TOO_MANY);
                continue;
            }
            if (!orca_obstacles_polygon_valid(poly.v)) {
                atomicOr(&orca_obstacles_best, ORCA_OBSTACLES_DEGENERATE);
            }
            let first = 4u * p;
            for (var i = 0u; i < 4u; i++) {
                let c = orca_obstacles_corner(poly.v, i);
                orca_obstacles_write_vertex(s, first + i, poly.v[i], c.dir, first + (i + 1u) % 4u, first + (i + 3u) % 4u, c.convex);
                scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, first + i)] = first + i;
            }
        }
        present += orca_obstacles_sides_before(end - k0).x;
        // Every lane has read the masks before the next run clears them.
        workgroupBarrier();
    }
    return present;
}

// `orca_obstacles_rebuild_if_dirty` of `wanted` (an environment, ORCA_OBSTACLES_SKIP or NONE:
// lane 0's is taken) by every lane of the workgroup, called by all of them together, with the
// same bits: lane 0 gathers the polygons and checks them, the lanes add a polygon each, and each
// tree node's split is chosen (`orca_obstacles_choose_on_lanes`) and made
// (`orca_obstacles_split_on_lanes`) on all the lanes, its children's lists moved into the arena
// by all of them and pushed by lane 0; the lanes store a vertex each. A node of n <= 32 edges is
// about n / 2 steps and a few barriers on a lane, where one lane took up to n² steps to choose and
// n to split. Whether `wanted` was not NONE (the value is the workgroup's own).
fn orca_obstacles_rebuild_on_lanes(wanted: u32, lane: u32) -> bool {
    if (lane == 0u) {
        var dirty = 0u;
        if (wanted < ORCA_OBSTACLES_SKIP && su[batch.c_obstacles_dirty + wanted] != 0u) {
            dirty = 1u;
        }
        orca_obstacles_turn = vec2<u32>(wanted, dirty);
    }
    let turn = workgroupUniformLoad(&orca_obstacles_turn);
    if (turn.x == NONE) {
        return false;
    }
    if (turn.y == 0u) {
        return true;
    }
    let e = turn.x;
    let s = orca_obstacles_set(e);
    if (lane == 0u) {
        orca_obstacles_poison_region(e);
        // The old count, which lane 0 overwrites at the end, handed to every lane through
        // workgroup memory: a lane's own read of the storage word, ordered only by workgroup
        // barriers against that write, could be moved after it.
        let count = su[batch.c_n_obstacle_vertices + e];
        orca_obstacles_node = vec2<u32>(orca_obstacles_raw_count(e), count);
        atomicStore(&orca_obstacles_best, 0u);
    }
    let first = workgroupUniformLoad(&orca_obstacles_node);
    let raw = first.x;
    let old = first.y;
    let polygons = orca_obstacles_add_on_lanes(e, s, raw, lane);
    var stack: OrcaObstaclesStack;
    if (lane == 0u) {
        let failed = atomicLoad(&orca_obstacles_best);
        scratch[s + 1u] = 0u;
        if ((failed & ORCA_OBSTACLES_TOO_MANY) != 0u) {
            scratch[s + 1u] |= ORCA_OVERFLOW_OBSTACLE_VERTICES;
        }
        if ((failed & ORCA_OBSTACLES_DEGENERATE) != 0u) {
            scratch[s + 1u] |= ORCA_OBSTACLES_INVALID;
        }
        let n = select(4u * polygons, 0u, failed != 0u);
        scratch[s] = n;
        stack = orca_obstacles_root(e, n);
    }
    loop {
        if (lane == 0u) {
            orca_obstacles_node = orca_obstacles_pop(e, &stack);
            atomicStore(&orca_obstacles_best, 0xffffffffu);
        }
        if (lane < ORCA_OBSTACLES_MASK_WORDS) {
            atomicStore(&orca_obstacles_left[lane], 0u);
            atomicStore(&orca_obstacles_right[lane], 0u);
        }
        let node = workgroupUniformLoad(&orca_obstacles_node);
        if (node.y == 0u) {
            break;
        }
        orca_obstacles_choose_on_lanes(e, s, node, lane);
        let chosen = orca_obstacles_split_of(atomicLoad(&orca_obstacles_best));
        let fits = orca_obstacles_split_on_lanes(e, s, node, chosen, lane);
        workgroupBarrier();
        // The children from `tmp` into the arena where the node's list was: the right list, then
        // the left (none where the split did not fit: the build stops).
        var children = 0u;
        if (fits) {
            children = chosen.y + chosen.z;
        }
        for (var k = lane; k < children; k += WORKGROUP_SIZE) {
            var src = k - chosen.z;
            if (k < chosen.z) {
                src = chosen.y + k;
            }
            scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_ARENA, node.x + k)] =
                scratch[orca_obstacles_stack(e, ORCA_OBSTACLES_TMP, src)];
        }
        if (lane == 0u) {
            if (fits) {
                orca_obstacles_push_children(e, chosen.y, chosen.z, &stack);
            } else {
                stack.depth = 0u;
            }
        }
    }
    orca_obstacles_store_part(e, old, lane, WORKGROUP_SIZE);
    if (lane == 0u) {
        su[batch.c_n_obstacle_vertices + e] = orca_obstacles_stored_count(s);
        orca_obstacles_clear_flag(e);
    }
    return true;
}
