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
// * `orca_obstacles_rebuild_if_dirty(e: u32)`: Rust `rebuild_if_dirty`: when `obstacles_dirty`
//   is obs, every polygon of environment e processed into the `ov_*` columns and
//   `n_obstacle_vertices`, and the flag cleared.
// * `orca_obstacles_raw_count(e: u32) -> u32` and `orca_obstacles_polygon(e: u32, k: u32) ->
//   OrcaObstaclePolygon`: Rust `for_each_polygon` as an indexed walk. For k in
//   0..orca_obstacles_raw_count(e), in order, the polygons whose `present` is true are those
//   `for_each_polygon` visits, in its order (0.1.1's: tables, free laptops, plants, walls, laptop
//   users, standing groups); `seen_as_rect` says whether a field of view tests it as `rect` (a
//   table, laptop or wall) or as `disc` (a plant, laptop use or standing group), `v` holds its
//   four corners counter-clockwise.
// * `orca_obstacles_push(list: ptr<function, OrcaObstaclePolygons>, v: array<vec2<f32>, 4>)`:
//   appends one polygon to a list (a fresh `var` is empty).
// * `orca_obstacles_process(polygons: ptr<function, OrcaObstaclePolygons>,
//   obs: ptr<function, OrcaObstacleSet>)`: Rust `process_obstacles` of any polygon list into a
//   function-scope obs: `len` processed vertices (input vertices, then split vertices in RVO2's
//   order) in `point`, `dir`, `next`, `prev`, `convex` (the `ov_*` layout, local indices), and
//   `overflow` (0: the CPU's result; see below). A walker with a restricted field of view
//   (Rust `with_visible`) pushes the polygons it sees and processes them with this.
// * `orca_obstacles_set_vertex(obs: ptr<function, OrcaObstacleSet>, i: u32) -> OrcaVertex`:
//   what an ORCA obstacle line reads of vertex i of such a obs (common/orca.wgsl's building
//   blocks: `orca_obstacle_neighbor_candidate` takes `point[i]` and `point[next[i]]`,
//   `orca_push_obstacle_line` two of these).
// * `orca_obstacles_box_distance_sq(pos: vec2<f32>, v: array<vec2<f32>, 4>) -> f32`: Rust
//   `box_distance_sq` (squared distance to the polygon's bounding box, 0 inside).
//
// Capacities and overflow. The processed obs holds orca_obstacles_cap() = batch.s_ov_x vertices, the
// per-environment capacity of the `ov_*` columns (Rust `store` asserts the same bound); a list
// holds batch.s_ov_x / 8 polygons (`Caps` gives every polygon room for 8 processed vertices: its 4
// and as many split vertices, so an environment never has more). Large private arrays make
// llvmpipe's compile time grow quickly: keep one call site of `orca_obstacles_process` per
// shader where possible (Mesa inlines every call). The tree
// build keeps its edge lists on an explicit stack: a node's list is popped, split into its left
// and right lists, and those are pushed (right first), so the left subtree is built completely
// before the right one, as in the recursive Rust. The lists on the stack hold distinct vertex
// ids (each edge goes to one side; a split edge's two pieces have two ids), so the stack never
// holds more than `len` <= batch.s_ov_x ids or lists: its arrays of batch.s_ov_x cannot overflow unless the
// vertex obs does. Where Rust panics (a processed obs larger than batch.s_ov_x; a degenerate or
// non-finite polygon, which `validate_polygons` rejects), the obs gets a non-zero `overflow`
// (ORCA_OVERFLOW_OBSTACLE_VERTICES, ORCA_OBSTACLES_INVALID) and processing stops; a caller of
// `orca_obstacles_process` must treat it as an error (an ORCA result that ORs it in is NaN by
// common/orca.wgsl's convention). `orca_obstacles_rebuild_if_dirty` then poisons the columns:
// every one of the batch.s_ov_x vertices gets NaN coordinates and directions (`n_obstacle_vertices` =
// batch.s_ov_x), and `obstacles_dirty` is left at ORCA_OBSTACLES_FAILED (2) instead of 0, so the host
// can see it. Neither can happen under the shipped capacities (the CPU would have panicked).
//
// Loop budget on lavapipe: llvmpipe stops every loop of an invocation after 65535 loop iterations
// in total (docs/ARCHITECTURE.md). `choose_split` costs up to n² iterations per node (fewer with
// RVO2's early exit); the shipped configs' rebuilds (tests/suite/step/social_events/gpu.rs and
// formation.rs, stress included) stay within it, but a much larger obstacle set could exceed it
// there.

// Sizes of the arrays below: compile-time size classes (backend::wgsl::SizeClasses), at least
// the batch's capacities, which every count is compared with (`orca_obstacles_cap`,
// `orca_obstacles_max_polygons`).
const ORCA_OBSTACLES_ARRAY: u32 = ARRAY_OBSTACLE_VERTICES;
const ORCA_OBSTACLES_POLYGONS_ARRAY: u32 = ARRAY_OBSTACLE_VERTICES / 8u;

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
// `obstacles_dirty` after a rebuild that failed (see the header).
const ORCA_OBSTACLES_FAILED: u32 = 2u;
const ORCA_OBSTACLES_EXP_MASK: u32 = 0x7f800000u;

// One polygon of `for_each_polygon` (see the header).
struct OrcaObstaclePolygon {
    present: bool,
    seen_as_rect: bool,
    rect: Rect,
    disc: Disc,
    v: array<vec2<f32>, 4>,
}

// Input polygons (quadrilaterals, counter-clockwise) of `orca_obstacles_process`.
struct OrcaObstaclePolygons {
    len: u32,
    overflow: u32,
    v: array<array<vec2<f32>, 4>, ORCA_OBSTACLES_POLYGONS_ARRAY>,
}

// Rust `ObstacleSet`'s vertex columns (the tree itself is not kept: nothing reads it).
struct OrcaObstacleSet {
    len: u32,
    overflow: u32,
    point: array<vec2<f32>, ORCA_OBSTACLES_ARRAY>,
    dir: array<vec2<f32>, ORCA_OBSTACLES_ARRAY>,
    next: array<u32, ORCA_OBSTACLES_ARRAY>,
    prev: array<u32, ORCA_OBSTACLES_ARRAY>,
    convex: array<u32, ORCA_OBSTACLES_ARRAY>,
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
    let h = e * batch.s_h_x + su[batch.c_lu_human + u];
    let l = e * batch.s_l_x + su[batch.c_lu_laptop + u];
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
        if (su[batch.c_l_user + e * batch.s_l_x + k] == NONE) {
            return orca_obstacles_rect_polygon(world_laptop_rect(e, k));
        }
        return none;
    }
    k -= n_laptops;
    let n_plants = su[batch.c_n_plants + e];
    if (k < n_plants) {
        let i = e * batch.s_p_x + k;
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
        let u = e * batch.s_lu_human + k;
        let h = e * batch.s_h_x + su[batch.c_lu_human + u];
        return orca_obstacles_disc_polygon(
            orca_obstacles_laptop_use_disc(e, u),
            orca_obstacles_square(sf[batch.c_h_x + h], sf[batch.c_h_y + h], params.laptop_user_half_side),
        );
    }
    k -= n_users;
    let g = e * batch.s_g_x + k;
    if (k < su[batch.c_n_groups + e] && su[batch.c_g_kind + g] == GROUP_STANDING) {
        // Rust `perception::group_disc`.
        let d = Disc(sf[batch.c_g_x + g], sf[batch.c_g_y + g], params.group_radius);
        return orca_obstacles_disc_polygon(d, orca_obstacles_square(sf[batch.c_g_x + g], sf[batch.c_g_y + g], params.group_radius));
    }
    return none;
}

// Appends polygon `v` to `list`; past `orca_obstacles_max_polygons()` it flags the overflow.
fn orca_obstacles_push(list: ptr<function, OrcaObstaclePolygons>, v: array<vec2<f32>, 4>) {
    if ((*list).len == orca_obstacles_max_polygons()) {
        (*list).overflow |= ORCA_OVERFLOW_OBSTACLE_VERTICES;
        return;
    }
    (*list).v[(*list).len] = v;
    (*list).len += 1u;
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

fn orca_obstacles_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & ORCA_OBSTACLES_EXP_MASK) != ORCA_OBSTACLES_EXP_MASK;
}

// Rust `validate_polygons` for quadrilaterals: true if every vertex is finite and every edge's
// squared length a positive finite f32.
fn orca_obstacles_valid(polygons: ptr<function, OrcaObstaclePolygons>) -> bool {
    for (var p = 0u; p < (*polygons).len; p++) {
        for (var k = 0u; k < 4u; k++) {
            let a = (*polygons).v[p][k];
            if (!orca_obstacles_finite(a.x) || !orca_obstacles_finite(a.y)) {
                return false;
            }
        }
        for (var k = 0u; k < 4u; k++) {
            let a = (*polygons).v[p][k];
            let b = (*polygons).v[p][(k + 1u) % 4u];
            let len_sq = orca_abs_sq(b - a);
            if (!(len_sq > 0.0 && orca_obstacles_finite(len_sq))) {
                return false;
            }
        }
    }
    return true;
}

// Rust `ObstacleSet::push_vertex`; false (and the overflow flagged) when the obs is full.
fn orca_obstacles_push_vertex(
    obs: ptr<function, OrcaObstacleSet>,
    p: vec2<f32>,
    dir: vec2<f32>,
    next: u32,
    prev: u32,
    convex: u32,
) -> bool {
    let i = (*obs).len;
    if (i == orca_obstacles_cap()) {
        (*obs).overflow |= ORCA_OVERFLOW_OBSTACLE_VERTICES;
        return false;
    }
    (*obs).point[i] = p;
    (*obs).dir[i] = dir;
    (*obs).next[i] = next;
    (*obs).prev[i] = prev;
    (*obs).convex[i] = convex;
    (*obs).len = i + 1u;
    return true;
}

// Rust `add_polygon` (RVO2's `addObstacle`) for one quadrilateral.
fn orca_obstacles_add_polygon(obs: ptr<function, OrcaObstacleSet>, v: array<vec2<f32>, 4>) {
    let n = 4u;
    let first = (*obs).len;
    for (var i = 0u; i < n; i++) {
        var prev_i = i - 1u;
        if (i == 0u) {
            prev_i = n - 1u;
        }
        var next_i = i + 1u;
        if (i == n - 1u) {
            next_i = 0u;
        }
        let p = v[i];
        let p_prev = v[prev_i];
        let p_next = v[next_i];
        let dir = orca_normalize(p_next - p);
        var convex = 0u;
        if (orca_left_of(p_prev, p, p_next) >= 0.0) {
            convex = 1u;
        }
        if (!orca_obstacles_push_vertex(obs, p, dir, first + next_i, first + prev_i, convex)) {
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
fn orca_obstacles_edge_sides(obs: ptr<function, OrcaObstacleSet>, i1: u32, j1: u32) -> vec2<f32> {
    let a = (*obs).point[i1];
    let b = (*obs).point[(*obs).next[i1]];
    let s1 = orca_left_of(a, b, (*obs).point[j1]);
    let s2 = orca_left_of(a, b, (*obs).point[(*obs).next[j1]]);
    return vec2<f32>(s1, s2);
}

// Lexicographic `(a0, a1) < (b0, b1)` of Rust's tuple keys.
fn orca_obstacles_key_less(a0: u32, a1: u32, b0: u32, b1: u32) -> bool {
    return a0 < b0 || (a0 == b0 && a1 < b1);
}

// Rust `choose_split` over the list `arena[start..start + n]`: (position, L, R).
fn orca_obstacles_choose_split(
    obs: ptr<function, OrcaObstacleSet>,
    arena: ptr<function, array<u32, ORCA_OBSTACLES_ARRAY>>,
    start: u32,
    n: u32,
) -> vec3<u32> {
    var best = 0u;
    var min_left = n;
    var min_right = n;
    for (var i = 0u; i < n; i++) {
        let i1 = (*arena)[start + i];
        let best0 = max(min_left, min_right);
        let best1 = min(min_left, min_right);
        var left = 0u;
        var right = 0u;
        for (var j = 0u; j < n; j++) {
            if (i == j) {
                continue;
            }
            let s = orca_obstacles_edge_sides(obs, i1, (*arena)[start + j]);
            let side = orca_obstacles_classify(s.x, s.y);
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

// Rust `split_edge`: splits edge j1 -> next(j1) where it crosses the line of edge i1 -> next(i1);
// the fresh vertex's id, or NONE when the obs is full (overflow flagged).
fn orca_obstacles_split_edge(obs: ptr<function, OrcaObstacleSet>, i1: u32, j1: u32) -> u32 {
    let j2 = (*obs).next[j1];
    let a = (*obs).point[i1];
    let b = (*obs).point[(*obs).next[i1]];
    let pj1 = (*obs).point[j1];
    let pj2 = (*obs).point[j2];
    let t = orca_det(b - a, pj1 - a) / orca_det(b - a, pj1 - pj2);
    let split_point = pj1 + t * (pj2 - pj1);
    let fresh = (*obs).len;
    let dir = (*obs).dir[j1];
    if (!orca_obstacles_push_vertex(obs, split_point, dir, j2, j1, 1u)) {
        return NONE;
    }
    (*obs).next[j1] = fresh;
    (*obs).prev[j2] = fresh;
    return fresh;
}

// Rust `process_obstacles` (see the header).
fn orca_obstacles_process(polygons: ptr<function, OrcaObstaclePolygons>, obs: ptr<function, OrcaObstacleSet>) {
    (*obs).len = 0u;
    (*obs).overflow = (*polygons).overflow;
    if (!orca_obstacles_valid(polygons)) {
        (*obs).overflow |= ORCA_OBSTACLES_INVALID;
    }
    if ((*obs).overflow != 0u) {
        return;
    }
    for (var p = 0u; p < (*polygons).len; p++) {
        orca_obstacles_add_polygon(obs, (*polygons).v[p]);
    }
    if ((*obs).overflow != 0u) {
        return;
    }

    // `build_node` from the root list of every vertex, with an explicit stack of edge lists
    // (`arena[..end]`, list lengths in `lens[..depth]`, the top list last).
    var arena: array<u32, ORCA_OBSTACLES_ARRAY>;
    var lens: array<u32, ORCA_OBSTACLES_ARRAY>;
    var tmp: array<u32, ORCA_OBSTACLES_ARRAY>;
    let n = (*obs).len;
    for (var i = 0u; i < n; i++) {
        arena[i] = i;
    }
    var end = n;
    var depth = 0u;
    if (n > 0u) {
        lens[0] = n;
        depth = 1u;
    }
    while (depth > 0u) {
        depth -= 1u;
        let len = lens[depth];
        let start = end - len;
        let chosen = orca_obstacles_choose_split(obs, &arena, start, len);
        let split = chosen.x;
        let n_left = chosen.y;
        let n_right = chosen.z;
        let i1 = arena[start + split];
        // Child lists into `tmp`: left at 0.., right at n_left...
        var lc = 0u;
        var rc = 0u;
        for (var j = 0u; j < len; j++) {
            if (j == split) {
                continue;
            }
            let j1 = arena[start + j];
            let s = orca_obstacles_edge_sides(obs, i1, j1);
            let side = orca_obstacles_classify(s.x, s.y);
            var to_left = NONE;
            var to_right = NONE;
            if (side == 0u) {
                to_left = j1;
            } else if (side == 1u) {
                to_right = j1;
            } else {
                let fresh = orca_obstacles_split_edge(obs, i1, j1);
                if (fresh == NONE) {
                    return;
                }
                if (s.x > 0.0) {
                    to_left = j1;
                    to_right = fresh;
                } else {
                    to_left = fresh;
                    to_right = j1;
                }
            }
            if (to_left != NONE) {
                tmp[lc] = to_left;
                lc += 1u;
            }
            if (to_right != NONE) {
                tmp[n_left + rc] = to_right;
                rc += 1u;
            }
        }
        // Pop this list, push the right list, then the left one (built next, completely).
        // Cannot overflow (see the header); checked all the same.
        if (lc != n_left || rc != n_right || start + n_left + n_right > orca_obstacles_cap()) {
            (*obs).overflow |= ORCA_OVERFLOW_OBSTACLE_VERTICES;
            return;
        }
        end = start;
        if (n_right > 0u) {
            for (var k = 0u; k < n_right; k++) {
                arena[end + k] = tmp[n_left + k];
            }
            end += n_right;
            lens[depth] = n_right;
            depth += 1u;
        }
        if (n_left > 0u) {
            for (var k = 0u; k < n_left; k++) {
                arena[end + k] = tmp[k];
            }
            end += n_left;
            lens[depth] = n_left;
            depth += 1u;
        }
    }
}

// What `orca_obstacle_line` reads of vertex i of a processed obs.
fn orca_obstacles_set_vertex(obs: ptr<function, OrcaObstacleSet>, i: u32) -> OrcaVertex {
    return orca_vertex(i, (*obs).point[i], (*obs).dir[i], (*obs).dir[(*obs).prev[i]], (*obs).convex[i]);
}

// ---- orca_obstacles.rs: the environment's obs ----------------------------------------------------

// Every polygon of `for_each_polygon` for environment e into `list`.
fn orca_obstacles_gather(e: u32, list: ptr<function, OrcaObstaclePolygons>) {
    let raw = orca_obstacles_raw_count(e);
    for (var k = 0u; k < raw; k++) {
        let poly = orca_obstacles_polygon(e, k);
        if (poly.present) {
            orca_obstacles_push(list, poly.v);
        }
    }
}

// Rust `store` (a obs with an overflow poisons the columns instead; see the header).
fn orca_obstacles_store(e: u32, obs: ptr<function, OrcaObstacleSet>) {
    let b = e * batch.s_ov_x;
    if ((*obs).overflow != 0u) {
        for (var k = 0u; k < batch.s_ov_x; k++) {
            sf[batch.c_ov_x + b + k] = math_nan();
            sf[batch.c_ov_y + b + k] = math_nan();
            sf[batch.c_ov_dir_x + b + k] = math_nan();
            sf[batch.c_ov_dir_y + b + k] = math_nan();
            su[batch.c_ov_next + b + k] = (k + 1u) % orca_obstacles_cap();
            su[batch.c_ov_prev + b + k] = (k + orca_obstacles_cap() - 1u) % orca_obstacles_cap();
            su[batch.c_ov_convex + b + k] = 1u;
        }
        su[batch.c_n_obstacle_vertices + e] = batch.s_ov_x;
        return;
    }
    let n = (*obs).len;
    // A smaller set than before: its old tail becomes unused slots, which hold zeros.
    let old = min(su[batch.c_n_obstacle_vertices + e], batch.s_ov_x);
    for (var k = n; k < old; k++) {
        sf[batch.c_ov_x + b + k] = 0.0;
        sf[batch.c_ov_y + b + k] = 0.0;
        sf[batch.c_ov_dir_x + b + k] = 0.0;
        sf[batch.c_ov_dir_y + b + k] = 0.0;
        su[batch.c_ov_next + b + k] = 0u;
        su[batch.c_ov_prev + b + k] = 0u;
        su[batch.c_ov_convex + b + k] = 0u;
    }
    for (var k = 0u; k < n; k++) {
        sf[batch.c_ov_x + b + k] = (*obs).point[k].x;
        sf[batch.c_ov_y + b + k] = (*obs).point[k].y;
        sf[batch.c_ov_dir_x + b + k] = (*obs).dir[k].x;
        sf[batch.c_ov_dir_y + b + k] = (*obs).dir[k].y;
        su[batch.c_ov_next + b + k] = (*obs).next[k];
        su[batch.c_ov_prev + b + k] = (*obs).prev[k];
        su[batch.c_ov_convex + b + k] = (*obs).convex[k];
    }
    su[batch.c_n_obstacle_vertices + e] = n;
}

// Rust `rebuild_if_dirty` (see the header).
fn orca_obstacles_rebuild_if_dirty(e: u32) {
    if (su[batch.c_obstacles_dirty + e] == 0u) {
        return;
    }
    var polygons: OrcaObstaclePolygons;
    orca_obstacles_gather(e, &polygons);
    var obs: OrcaObstacleSet;
    orca_obstacles_process(&polygons, &obs);
    orca_obstacles_store(e, &obs);
    if (obs.overflow != 0u) {
        su[batch.c_obstacles_dirty + e] = ORCA_OBSTACLES_FAILED;
    } else {
        su[batch.c_obstacles_dirty + e] = 0u;
    }
}
