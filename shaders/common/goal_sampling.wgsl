// requires: common/world.wgsl
// requires: common/place.wgsl
//
// Twin of src/systems/goals.rs's `sample_goal` and `touches_goal` and of src/systems/world.rs's
// `blocks_goal` (for the disc shapes the step tests) and `blocker_rect`: goal sampling, shared by
// the stages that give humans new goals (goals, social events, formation). Library file (no
// entry point, reads the prelude's `sf`/`su`/`params`). Same operations in the same order as the
// Rust files; change them together.

// Rust `Option<Disc>` of `sample_goal`.
struct GoalSample {
    found: bool,
    disc: Disc,
}

// Rust `world::blocker_rect`: spawn blocker b (local) of environment e.
fn world_blocker_rect(e: u32, b: u32) -> Rect {
    let i = at_blocker(e, b);
    return geo_rect_new(sf[batch.c_b_x + i], sf[batch.c_b_y + i], sf[batch.c_b_theta + i], sf[batch.c_b_length + i], sf[batch.c_b_width + i]);
}

// Rust `world::blocks_goal` for `shape = Shape::Disc(d)`: does d intersect the robot, a human, a
// plant, a wall, a table, a laptop or a spawn blocker? (No `return` inside a loop here and
// below: these run inside the samplers' loops, and Mesa 22.3's lowering of early returns from
// inlined functions nested in loops cut the callers' loops short on lavapipe.)
fn world_blocks_goal(e: u32, d: Disc) -> bool {
    var hit = geo_disc_disc(Disc(sf[batch.c_robot_x + e], sf[batch.c_robot_y + e], params.robot_radius), d);
    for (var i = at_human(e, 0u); i < at_human(e, su[batch.c_n_humans + e]) && !hit; i += batch.k_human) {
        hit = geo_disc_disc(Disc(sf[batch.c_h_x + i], sf[batch.c_h_y + i], params.human_radius), d);
    }
    for (var i = at_plant(e, 0u); i < at_plant(e, su[batch.c_n_plants + e]) && !hit; i += batch.k_plant) {
        hit = geo_disc_disc(Disc(sf[batch.c_p_x + i], sf[batch.c_p_y + i], params.plant_radius), d);
    }
    for (var w = 0u; w < su[batch.c_n_walls + e] && !hit; w++) {
        hit = geo_disc_rect(d, world_wall_rect(e, w));
    }
    for (var k = 0u; k < su[batch.c_n_tables + e] && !hit; k++) {
        hit = geo_disc_rect(d, world_table_rect(e, k));
    }
    for (var k = 0u; k < su[batch.c_n_laptops + e] && !hit; k++) {
        hit = geo_disc_rect(d, world_laptop_rect(e, k));
    }
    for (var b = 0u; b < su[batch.c_n_blockers + e] && !hit; b++) {
        hit = geo_disc_rect(d, world_blocker_rect(e, b));
    }
    return hit;
}

// Rust `touches_goal`: does d touch a current goal (the robot's, a lone human's, a moving
// group's)?
fn goals_touches_goal(e: u32, d: Disc) -> bool {
    var hit = geo_disc_disc(d, Disc(sf[batch.c_goal_x + e], sf[batch.c_goal_y + e], params.goal_radius));
    let n_lone = su[batch.c_n_static + e] + su[batch.c_n_dynamic + e];
    for (var i = at_human(e, 0u); i < at_human(e, n_lone) && !hit; i += batch.k_human) {
        hit = geo_disc_disc(d, Disc(sf[batch.c_h_goal_x + i], sf[batch.c_h_goal_y + i], params.human_goal_radius));
    }
    for (var g = at_group(e, 0u); g < at_group(e, su[batch.c_n_groups + e]) && !hit; g += batch.k_group) {
        hit = su[batch.c_g_kind + g] == GROUP_MOVING
            && geo_disc_disc(d, Disc(sf[batch.c_g_goal_x + g], sf[batch.c_g_goal_y + g], params.group_goal_radius));
    }
    return hit;
}

// Rust `sample_goal`: a goal disc of radius r free of every entity and every current goal, or
// none after PLACE_MAX_TRIES tries.
fn goals_sample_goal(e: u32, rng: ptr<function, RngStream>, r: f32) -> GoalSample {
    let area = place_sampling_box(sf[batch.c_map_x + e], sf[batch.c_map_y + e]);
    var out = GoalSample(false, Disc(0.0, 0.0, r));
    for (var t = 0u; t < PLACE_MAX_TRIES && !out.found; t++) {
        let p = place_box_point(area, rng);
        let d = Disc(p.x, p.y, r);
        if (!world_blocks_goal(e, d) && !goals_touches_goal(e, d)) {
            out = GoalSample(true, d);
        }
    }
    return out;
}
