// requires: common/orca.wgsl
// requires: common/perception.wgsl
// requires: common/orca_obstacles.wgsl
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
// range, else the visible polygons processed afresh (`orca_world_visible`, then
// common/orca_obstacles.wgsl's `orca_obstacles_process`, RVO2's `processObstacles`). A processed
// set that would overflow its capacity (batch.s_ov_x vertices, as the `ov_*` columns) makes the
// velocity NaN, like the list overflows below.
//
// Candidate identity. Rust collects the candidates into a list and selects by list index; the
// selection only compares distances (ties keep the visiting order), so here a candidate is
// visited in the same order and identified by a tag instead of its list index:
// ORCA_WORLD_HUMAN | slot, ORCA_WORLD_ROBOT, ORCA_WORLD_GROUP | slot (global slots: element
// indices `at_human(e, k)`, `at_group(e, k)`, compared only for equality, never ordered).
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
        sf[batch.c_orca_max_speed + e],
        sf[batch.c_orca_neighbor_dist + e],
        su[batch.c_n_humans + e],
        sf[batch.c_orca_time_horizon + e],
        sf[batch.c_orca_time_horizon_obst + e],
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
            vel = vec2<f32>(sf[batch.c_h_vx + slot], sf[batch.c_h_vy + slot]);
        }
        return OrcaNeighbor(vec2<f32>(sf[batch.c_h_x + slot], sf[batch.c_h_y + slot]), vel, params.human_radius);
    }
    if (kind == ORCA_WORLD_ROBOT) {
        // Rust `robot_motion::robot_world_velocity`.
        if (actual) {
            vel = vec2<f32>(sf[batch.c_robot_wvx + e], sf[batch.c_robot_wvy + e]);
        }
        return OrcaNeighbor(vec2<f32>(sf[batch.c_robot_x + e], sf[batch.c_robot_y + e]), vel, params.robot_radius);
    }
    if (actual) {
        vel = vec2<f32>(sf[batch.c_g_vx + slot], sf[batch.c_g_vy + slot]);
    }
    return OrcaNeighbor(vec2<f32>(sf[batch.c_g_x + slot], sf[batch.c_g_y + slot]), vel, orca_world_group_agent_radius());
}

// Rust `gather` then `select`: RVO2's neighbour selection for `first` over the other agents in
// 0.1.1's order (lone humans, the robot, moving groups), nearest first, ties in that order.
// `list` must be empty.
fn orca_world_select(e: u32, first: OrcaAgent, others: OrcaWorldOthers, list: ptr<function, OrcaAgentNeighbors>) {
    var range_sq = orca_agent_range_sq(first.neighbor_dist);
    let n_lone = su[batch.c_n_static + e] + su[batch.c_n_dynamic + e];
    for (var i = at_human(e, 0u); i < at_human(e, n_lone); i += batch.k_human) {
        if (i == others.skip_human || !perception_sees_human(others.view, e, i)) {
            continue;
        }
        let pos = vec2<f32>(sf[batch.c_h_x + i], sf[batch.c_h_y + i]);
        orca_agent_neighbor_candidate(list, first.max_neighbors, first.pos, ORCA_WORLD_HUMAN | i, pos, &range_sq);
    }
    if (others.robot) {
        let pos = vec2<f32>(sf[batch.c_robot_x + e], sf[batch.c_robot_y + e]);
        orca_agent_neighbor_candidate(list, first.max_neighbors, first.pos, ORCA_WORLD_ROBOT, pos, &range_sq);
    }
    for (var g = at_group(e, 0u); g < at_group(e, su[batch.c_n_groups + e]); g += batch.k_group) {
        if (su[batch.c_g_kind + g] != GROUP_MOVING || g == others.skip_group
            || !perception_maybe_sees_disc(others.view, perception_group_disc(g))) {
            continue;
        }
        let pos = vec2<f32>(sf[batch.c_g_x + g], sf[batch.c_g_y + g]);
        orca_agent_neighbor_candidate(list, first.max_neighbors, first.pos, ORCA_WORLD_GROUP | g, pos, &range_sq);
    }
}

// Processed obstacle vertex `v` (local index) of environment e, as `orca_obstacle_line` reads it.
fn orca_world_vertex(e: u32, v: u32) -> OrcaVertex {
    let g = at_obstacle_vertex(e, v);
    let prev = at_obstacle_vertex(e, su[batch.c_ov_prev + g]);
    return orca_vertex(
        v,
        vec2<f32>(sf[batch.c_ov_x + g], sf[batch.c_ov_y + g]),
        vec2<f32>(sf[batch.c_ov_dir_x + g], sf[batch.c_ov_dir_y + g]),
        vec2<f32>(sf[batch.c_ov_dir_x + prev], sf[batch.c_ov_dir_y + prev]),
        su[batch.c_ov_convex + g],
    );
}

// What Rust `with_visible` hands the solver: the cached set, no obstacles, or the visible subset
// processed afresh.
const ORCA_WORLD_OBSTACLES_CACHED: u32 = 0u;
const ORCA_WORLD_OBSTACLES_NONE: u32 = 1u;
const ORCA_WORLD_OBSTACLES_SUBSET: u32 = 2u;

// Rust `with_visible`'s choice for `agent` with view `v` in environment e: the polygons of Rust
// `for_each_polygon` (common/orca_obstacles.wgsl's indexed walk, in its order), each tested as
// the shape 0.1.1 sees; those seen are appended to list `seen` (empty on entry), in order.
fn orca_world_visible(e: u32, v: View, agent: OrcaAgent, seen: u32) -> u32 {
    // As RVO2's neighbour search, with Rust's margin `range_sq * (1.0 + 1e-3)`.
    let range_sq = orca_obstacle_range_sq(agent.time_horizon_obst, agent.max_speed, agent.radius);
    let reject_sq = range_sq * ORCA_OBSTACLE_REJECT_FACTOR;
    var all = 0u;
    var near = false;
    let raw = orca_obstacles_raw_count(e);
    for (var k = 0u; k < raw; k++) {
        let poly = orca_obstacles_polygon(e, k);
        if (!poly.present) {
            continue;
        }
        all += 1u;
        var sees: bool;
        if (poly.seen_as_rect) {
            sees = perception_sees_rect(v, poly.rect);
        } else {
            sees = perception_sees_disc(v, poly.disc);
        }
        if (sees) {
            near = near || orca_obstacles_box_distance_sq(agent.pos, poly.v) <= reject_sq;
            orca_obstacles_push(seen, poly.v);
        }
    }
    if (orca_obstacles_list_len(seen) == all && orca_obstacles_list_overflow(seen) == 0u) {
        return ORCA_WORLD_OBSTACLES_CACHED;
    }
    if (!near) {
        return ORCA_WORLD_OBSTACLES_NONE;
    }
    return ORCA_WORLD_OBSTACLES_SUBSET;
}

// Rust `OrcaWorld::velocity`: the new velocity (m/s) of `first` in a simulator holding `others`
// of environment e, over e's processed obstacles or, with a view, those of Rust `with_visible`
// (`compute_new_velocity`).
fn orca_world_velocity(e: u32, first: OrcaAgent, others: OrcaWorldOthers) -> OrcaWorldVelocity {
    // The lists are not zeroed (src/backend/gpu/spirv.rs): their counts are cleared here.
    var nb: OrcaAgentNeighbors;
    orca_agent_neighbors_clear(&nb);
    orca_world_select(e, first, others, &nb);

    var obstacles = ORCA_WORLD_OBSTACLES_CACHED;
    if (others.view.some) {
        obstacles = orca_world_visible(e, others.view.view, first, orca_obstacles_list(e));
    }
    var lines: OrcaLines;
    orca_lines_clear(&lines);
    var onb: OrcaObstacleNeighbors;
    orca_obstacle_neighbors_clear(&onb);
    var set_overflow = 0u;
    let range_sq = orca_obstacle_range_sq(first.time_horizon_obst, first.max_speed, first.radius);
    if (obstacles == ORCA_WORLD_OBSTACLES_CACHED) {
        // `obstacle_neighbors` over the environment's vertices, in index order.
        for (var v = 0u; v < su[batch.c_n_obstacle_vertices + e]; v++) {
            let g = at_obstacle_vertex(e, v);
            let n = at_obstacle_vertex(e, su[batch.c_ov_next + g]);
            let a = vec2<f32>(sf[batch.c_ov_x + g], sf[batch.c_ov_y + g]);
            let b = vec2<f32>(sf[batch.c_ov_x + n], sf[batch.c_ov_y + n]);
            orca_obstacle_neighbor_candidate(&onb, first.pos, range_sq, v, a, b);
        }
        // `solve`: obstacle lines, then agent lines, then LP2/LP3.
        for (var k = 0u; k < onb.len; k++) {
            let o1 = onb.items[k].index;
            let o2 = su[batch.c_ov_next + at_obstacle_vertex(e, o1)];
            orca_push_obstacle_line(first, orca_world_vertex(e, o1), orca_world_vertex(e, o2), &lines);
        }
    } else if (obstacles == ORCA_WORLD_OBSTACLES_SUBSET) {
        // The visible polygons processed afresh (Rust `with_processed`), then the same as above
        // over that set.
        orca_obstacles_process(e);
        let visible = orca_obstacles_set(e);
        set_overflow = orca_obstacles_set_overflow(visible);
        for (var v = 0u; v < orca_obstacles_set_len(visible); v++) {
            let a = orca_obstacles_set_point(visible, v);
            let b = orca_obstacles_set_point(visible, orca_obstacles_set_next(visible, v));
            orca_obstacle_neighbor_candidate(&onb, first.pos, range_sq, v, a, b);
        }
        for (var k = 0u; k < onb.len; k++) {
            let o1 = onb.items[k].index;
            let o2 = orca_obstacles_set_next(visible, o1);
            orca_push_obstacle_line(first, orca_obstacles_set_vertex(visible, o1), orca_obstacles_set_vertex(visible, o2), &lines);
        }
    }
    lines.num_obstacle_lines = lines.len;
    for (var k = 0u; k < nb.len; k++) {
        orca_push_agent_line(first, orca_world_candidate(e, nb.items[k].index), params.dt, &lines);
    }
    let r = orca_solve(first, &lines);
    let overflow = r.overflow | nb.overflow | onb.overflow | set_overflow;
    if (overflow != 0u) {
        return OrcaWorldVelocity(vec2<f32>(math_nan(), math_nan()), overflow);
    }
    return OrcaWorldVelocity(r.velocity, 0u);
}
