// requires: common/orca.wgsl
// requires: common/perception.wgsl
// requires: common/world.wgsl
//
// Twin of src/systems/orca_world.rs (and of `with_visible` in src/systems/orca_obstacles.rs, the
// obstacles a walker with a narrow field of view takes part with).
//
// How SocNavGym 0.1.1 puts one agent into RVO2: a fresh simulator per agent per step whose other
// agents are the lone humans, optionally the robot, and the moving groups as super-agents, over
// the environment's processed obstacle vertices (`ov_*` columns). Only the first agent's new
// velocity is read, so this file picks its neighbours as RVO2 would (`select`, in the candidate
// order of `gather`) and runs the solver once through the building blocks of common/orca.wgsl,
// reading the packed state directly (no function-scope copies). Library file (no entry point),
// for stage shaders (it reads the prelude's `sf`/`su`/`params`). Same operations in the same
// order as the Rust files; change both in the same commit.
//
// Field of view. `OrcaWorldOthers.view` is Rust's `Others::view`: with `some == false` (moving
// groups, the shadow robot, walkers whose field of view sees everything) every lone human and
// moving group is a candidate and the environment's processed obstacles are used as they are.
// Otherwise only the lone humans and moving groups the view sees are candidates
// (common/perception.wgsl), and the obstacles are those of Rust `with_visible`: the cached set
// when every obstacle polygon is seen, none when none of those seen comes within the obstacle
// range, else the visible polygons processed afresh (`orca_world_visible`).
//
// Candidate identity. Rust collects the candidates into a list and selects by list index; the
// selection only compares distances (ties keep the visiting order), so here a candidate is
// visited in the same order and identified by a tag instead of its list index:
// ORCA_WORLD_HUMAN | slot, ORCA_WORLD_ROBOT, ORCA_WORLD_GROUP | slot (global slots).
//
// List limits. The lists are common/orca.wgsl's fixed-size ones. A list that would grow past its
// limit (more than ORCA_MAX_AGENT_NEIGHBORS selected agents: n_humans and the candidates in range
// both above it; more than ORCA_MAX_OBSTACLE_NEIGHBORS obstacle edges in range) makes the result
// differ from the CPU's; `orca_world_velocity` then returns a NaN velocity and a non-zero
// `overflow`, which the stages write as NaN, never a silently different value. It cannot happen
// when the capacities satisfy humans + groups + 1 <= ORCA_MAX_AGENT_NEIGHBORS and
// obstacle_vertices <= ORCA_MAX_OBSTACLE_NEIGHBORS (lines then fit too).

// No slot to skip (Rust `None`).
const ORCA_WORLD_NONE: u32 = 0xffffffffu;
// Candidate tags (see the header).
const ORCA_WORLD_KIND_MASK: u32 = 0xc0000000u;
const ORCA_WORLD_HUMAN: u32 = 0x00000000u;
const ORCA_WORLD_ROBOT: u32 = 0x40000000u;
const ORCA_WORLD_GROUP: u32 = 0x80000000u;

// Rust `Others`: global slots to skip (ORCA_WORLD_NONE: none), whether the robot is one of the
// agents, and the first agent's view (`perception_everything()`: it sees everything).
struct OrcaWorldOthers {
    skip_human: u32,
    skip_group: u32,
    robot: bool,
    view: MaybeView,
}

// The new velocity (m/s) and the OR of the ORCA_OVERFLOW_* bits (0: the CPU's result; otherwise
// the velocity is NaN).
struct OrcaWorldVelocity {
    velocity: vec2<f32>,
    overflow: u32,
}

// Rust `group_agent_radius`: member circle plus a human diameter (m).
fn orca_world_group_agent_radius() -> f32 {
    return params.group_radius + 2.0 * params.human_radius;
}

// Rust `preferred`: speed `speed` (m/s) from (x, y) towards (gx, gy); zero at the goal.
fn orca_world_preferred(x: f32, y: f32, gx: f32, gy: f32, speed: f32) -> vec2<f32> {
    let dx = gx - x;
    let dy = gy - y;
    let l = sqrt(dx * dx + dy * dy);
    if (l > 0.0) {
        return vec2<f32>(speed * (dx / l), speed * (dy / l));
    }
    return vec2<f32>(0.0, 0.0);
}

// Rust `agent`: an ORCA agent with environment e's per-episode parameters.
fn orca_world_agent(e: u32, pos: vec2<f32>, vel: vec2<f32>, pref: vec2<f32>, radius: f32) -> OrcaAgent {
    return OrcaAgent(
        pos,
        vel,
        pref,
        radius,
        sf[C_ORCA_MAX_SPEED + e],
        sf[C_ORCA_NEIGHBOR_DIST + e],
        su[C_N_HUMANS + e],
        sf[C_ORCA_TIME_HORIZON + e],
        sf[C_ORCA_TIME_HORIZON_OBST + e],
    );
}

// The candidate with tag `tag` as Rust `gather` builds it (velocities zero unless
// `orca_actual_velocity`).
fn orca_world_candidate(e: u32, tag: u32) -> OrcaNeighbor {
    let actual = params.orca_actual_velocity != 0u;
    let kind = tag & ORCA_WORLD_KIND_MASK;
    let slot = tag & ~ORCA_WORLD_KIND_MASK;
    var vel = vec2<f32>(0.0, 0.0);
    if (kind == ORCA_WORLD_HUMAN) {
        if (actual) {
            vel = vec2<f32>(sf[C_H_VX + slot], sf[C_H_VY + slot]);
        }
        return OrcaNeighbor(vec2<f32>(sf[C_H_X + slot], sf[C_H_Y + slot]), vel, params.human_radius);
    }
    if (kind == ORCA_WORLD_ROBOT) {
        // Rust `reward::robot_world_velocity`.
        if (actual) {
            vel = vec2<f32>(sf[C_ROBOT_WVX + e], sf[C_ROBOT_WVY + e]);
        }
        return OrcaNeighbor(vec2<f32>(sf[C_ROBOT_X + e], sf[C_ROBOT_Y + e]), vel, params.robot_radius);
    }
    if (actual) {
        vel = vec2<f32>(sf[C_G_VX + slot], sf[C_G_VY + slot]);
    }
    return OrcaNeighbor(vec2<f32>(sf[C_G_X + slot], sf[C_G_Y + slot]), vel, orca_world_group_agent_radius());
}

// Rust `gather` then `select`: RVO2's neighbour selection for `first` over the other agents in
// 0.1.1's order (lone humans, the robot, moving groups), nearest first, ties in that order.
// `list` must be empty.
fn orca_world_select(e: u32, first: OrcaAgent, others: OrcaWorldOthers, list: ptr<function, OrcaAgentNeighbors>) {
    var range_sq = orca_agent_range_sq(first.neighbor_dist);
    let hb = e * S_H_X;
    let n_lone = su[C_N_STATIC + e] + su[C_N_DYNAMIC + e];
    for (var i = hb; i < hb + n_lone; i++) {
        if (i == others.skip_human || !perception_sees_human(others.view, e, i)) {
            continue;
        }
        let pos = vec2<f32>(sf[C_H_X + i], sf[C_H_Y + i]);
        orca_agent_neighbor_candidate(list, first.max_neighbors, first.pos, ORCA_WORLD_HUMAN | i, pos, &range_sq);
    }
    if (others.robot) {
        let pos = vec2<f32>(sf[C_ROBOT_X + e], sf[C_ROBOT_Y + e]);
        orca_agent_neighbor_candidate(list, first.max_neighbors, first.pos, ORCA_WORLD_ROBOT, pos, &range_sq);
    }
    let gb = e * S_G_X;
    for (var g = gb; g < gb + su[C_N_GROUPS + e]; g++) {
        if (su[C_G_KIND + g] != GROUP_MOVING || g == others.skip_group
            || !perception_maybe_sees_disc(others.view, perception_group_disc(g))) {
            continue;
        }
        let pos = vec2<f32>(sf[C_G_X + g], sf[C_G_Y + g]);
        orca_agent_neighbor_candidate(list, first.max_neighbors, first.pos, ORCA_WORLD_GROUP | g, pos, &range_sq);
    }
}

// Processed obstacle vertex `v` (local index) of environment e, as `orca_obstacle_line` reads it.
fn orca_world_vertex(e: u32, v: u32) -> OrcaVertex {
    let ob = e * S_OV_X;
    let g = ob + v;
    let prev = ob + su[C_OV_PREV + g];
    return orca_vertex(
        v,
        vec2<f32>(sf[C_OV_X + g], sf[C_OV_Y + g]),
        vec2<f32>(sf[C_OV_DIR_X + g], sf[C_OV_DIR_Y + g]),
        vec2<f32>(sf[C_OV_DIR_X + prev], sf[C_OV_DIR_Y + prev]),
        su[C_OV_CONVEX + g],
    );
}

// What Rust `with_visible` hands the solver: the cached set, no obstacles, or the visible subset
// processed afresh.
const ORCA_WORLD_OBSTACLES_CACHED: u32 = 0u;
const ORCA_WORLD_OBSTACLES_NONE: u32 = 1u;
const ORCA_WORLD_OBSTACLES_SUBSET: u32 = 2u;
// Overflow bit (beyond common/orca.wgsl's): the visible subset must be processed, which this
// build cannot do yet (RVO2's obstacle processing in WGSL is missing).
const ORCA_WORLD_OVERFLOW_UNSUPPORTED: u32 = 0x100u;

// An obstacle polygon (Rust `orca_obstacles::Polygon`), counter-clockwise.
struct OrcaWorldPolygon {
    v: array<vec2<f32>, 4>,
}

// Rust `orca_obstacles::corners`: the rectangle's corners in 0.1.1's order.
fn orca_world_corners(r: Rect) -> OrcaWorldPolygon {
    return OrcaWorldPolygon(array<vec2<f32>, 4>(
        geo_rect_corner(r, 0u), geo_rect_corner(r, 1u), geo_rect_corner(r, 2u), geo_rect_corner(r, 3u),
    ));
}

// Rust `orca_obstacles::square`: the axis-aligned square of half-side `h` around (x, y),
// counter-clockwise from (+h, +h).
fn orca_world_square(x: f32, y: f32, h: f32) -> OrcaWorldPolygon {
    return OrcaWorldPolygon(array<vec2<f32>, 4>(
        vec2<f32>(x + h, y + h), vec2<f32>(x - h, y + h), vec2<f32>(x - h, y - h), vec2<f32>(x + h, y - h),
    ));
}

// Rust `orca_obstacles::box_distance_sq`: squared distance (m²) from `pos` to the polygon's
// bounding box (0 inside).
fn orca_world_box_distance_sq(pos: vec2<f32>, polygon: OrcaWorldPolygon) -> f32 {
    var lo = polygon.v[0];
    var hi = polygon.v[0];
    for (var k = 1u; k < 4u; k++) {
        lo.x = min(lo.x, polygon.v[k].x);
        lo.y = min(lo.y, polygon.v[k].y);
        hi.x = max(hi.x, polygon.v[k].x);
        hi.y = max(hi.y, polygon.v[k].y);
    }
    let dx = max(max(lo.x - pos.x, pos.x - hi.x), 0.0);
    let dy = max(max(lo.y - pos.y, pos.y - hi.y), 0.0);
    return dx * dx + dy * dy;
}

// The accumulator of Rust `with_visible`'s walk over the polygons: how many there are, how many
// the view sees, and whether one of those is near.
struct OrcaWorldSeen {
    all: u32,
    seen: u32,
    near: bool,
}

// The body of Rust `with_visible`'s closure for one polygon seen as `seen_as` (`seen`: whether
// the view sees that shape).
fn orca_world_count_polygon(acc: ptr<function, OrcaWorldSeen>, seen: bool, pos: vec2<f32>, reject_sq: f32, polygon: OrcaWorldPolygon) {
    (*acc).all += 1u;
    if (seen) {
        (*acc).near = (*acc).near || orca_world_box_distance_sq(pos, polygon) <= reject_sq;
        (*acc).seen += 1u;
    }
}

// Rust `with_visible`'s choice for `agent` with view `v` in environment e, walking the polygons of
// Rust `for_each_polygon` in its order (tables, free laptops, plants, walls, laptop users,
// standing groups), each tested as the shape 0.1.1 sees.
fn orca_world_visible(e: u32, v: View, agent: OrcaAgent) -> u32 {
    let range_sq = orca_obstacle_range_sq(agent.time_horizon_obst, agent.max_speed, agent.radius);
    // Rust `range_sq * (1.0 + 1e-3)`.
    let reject_sq = range_sq * ORCA_OBSTACLE_REJECT_FACTOR;
    let pos = agent.pos;
    var acc = OrcaWorldSeen(0u, 0u, false);
    for (var t = 0u; t < su[C_N_TABLES + e]; t++) {
        let r = world_table_rect(e, t);
        orca_world_count_polygon(&acc, perception_sees_rect(v, r), pos, reject_sq, orca_world_corners(r));
    }
    let lb = e * S_L_X;
    for (var l = 0u; l < su[C_N_LAPTOPS + e]; l++) {
        if (su[C_L_USER + lb + l] == NONE) {
            let r = world_laptop_rect(e, l);
            orca_world_count_polygon(&acc, perception_sees_rect(v, r), pos, reject_sq, orca_world_corners(r));
        }
    }
    let pb = e * S_P_X;
    for (var i = pb; i < pb + su[C_N_PLANTS + e]; i++) {
        let x = sf[C_P_X + i];
        let y = sf[C_P_Y + i];
        let r = params.plant_radius;
        orca_world_count_polygon(&acc, perception_sees_disc(v, Disc(x, y, r)), pos, reject_sq, orca_world_square(x, y, r));
    }
    for (var w = 0u; w < su[C_N_WALLS + e]; w++) {
        let r = world_wall_rect(e, w);
        orca_world_count_polygon(&acc, perception_sees_rect(v, r), pos, reject_sq, orca_world_corners(r));
    }
    let hb = e * S_H_X;
    let ub = e * S_LU_HUMAN;
    for (var u = ub; u < ub + su[C_N_LAPTOP_USERS + e]; u++) {
        let h = hb + su[C_LU_HUMAN + u];
        let seen = perception_sees_disc(v, perception_laptop_use_disc(e, u));
        orca_world_count_polygon(&acc, seen, pos, reject_sq, orca_world_square(sf[C_H_X + h], sf[C_H_Y + h], params.laptop_user_half_side));
    }
    let gb = e * S_G_X;
    for (var g = gb; g < gb + su[C_N_GROUPS + e]; g++) {
        if (su[C_G_KIND + g] == GROUP_STANDING) {
            let seen = perception_sees_disc(v, perception_group_disc(g));
            orca_world_count_polygon(&acc, seen, pos, reject_sq, orca_world_square(sf[C_G_X + g], sf[C_G_Y + g], params.group_radius));
        }
    }
    if (acc.seen == acc.all) {
        return ORCA_WORLD_OBSTACLES_CACHED;
    }
    if (!acc.near) {
        return ORCA_WORLD_OBSTACLES_NONE;
    }
    return ORCA_WORLD_OBSTACLES_SUBSET;
}

// Rust `OrcaWorld::velocity`: the new velocity (m/s) of `first` in a simulator holding `others`
// of environment e, over e's processed obstacles or, with a view, those of Rust `with_visible`
// (`compute_new_velocity`).
fn orca_world_velocity(e: u32, first: OrcaAgent, others: OrcaWorldOthers) -> OrcaWorldVelocity {
    var nb: OrcaAgentNeighbors;
    orca_world_select(e, first, others, &nb);

    var obstacles = ORCA_WORLD_OBSTACLES_CACHED;
    if (others.view.some) {
        obstacles = orca_world_visible(e, others.view.view, first);
    }
    var lines: OrcaLines;
    var proj: OrcaLines;
    var onb: OrcaObstacleNeighbors;
    var unsupported = 0u;
    if (obstacles == ORCA_WORLD_OBSTACLES_CACHED) {
        // `obstacle_neighbors` over the environment's vertices, in index order.
        let range_sq = orca_obstacle_range_sq(first.time_horizon_obst, first.max_speed, first.radius);
        let ob = e * S_OV_X;
        for (var v = 0u; v < su[C_N_OBSTACLE_VERTICES + e]; v++) {
            let g = ob + v;
            let n = ob + su[C_OV_NEXT + g];
            let a = vec2<f32>(sf[C_OV_X + g], sf[C_OV_Y + g]);
            let b = vec2<f32>(sf[C_OV_X + n], sf[C_OV_Y + n]);
            orca_obstacle_neighbor_candidate(&onb, first.pos, range_sq, v, a, b);
        }
        // `solve`: obstacle lines, then agent lines, then LP2/LP3.
        for (var k = 0u; k < onb.len; k++) {
            let o1 = onb.items[k].index;
            let o2 = su[C_OV_NEXT + ob + o1];
            orca_push_obstacle_line(first, orca_world_vertex(e, o1), orca_world_vertex(e, o2), &lines);
        }
    } else if (obstacles == ORCA_WORLD_OBSTACLES_SUBSET) {
        unsupported = ORCA_WORLD_OVERFLOW_UNSUPPORTED;
    }
    lines.num_obstacle_lines = lines.len;
    for (var k = 0u; k < nb.len; k++) {
        orca_push_agent_line(first, orca_world_candidate(e, nb.items[k].index), params.dt, &lines);
    }
    let r = orca_solve(first, &lines, &proj);
    let overflow = r.overflow | nb.overflow | onb.overflow | unsupported;
    if (overflow != 0u) {
        return OrcaWorldVelocity(vec2<f32>(math_nan(), math_nan()), overflow);
    }
    return OrcaWorldVelocity(r.velocity, 0u);
}
