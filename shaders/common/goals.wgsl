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
    let i = e * S_B_X + b;
    return geo_rect_new(sf[C_B_X + i], sf[C_B_Y + i], sf[C_B_THETA + i], sf[C_B_LENGTH + i], sf[C_B_WIDTH + i]);
}

// Rust `world::blocks_goal` for `shape = Shape::Disc(d)`: does d intersect the robot, a human, a
// plant, a wall, a table, a laptop or a spawn blocker? (No `return` inside a loop here and
// below: these run inside the samplers' loops, and Mesa 22.3's lowering of early returns from
// inlined functions nested in loops cut the callers' loops short on lavapipe.)
fn world_blocks_goal(e: u32, d: Disc) -> bool {
    var hit = geo_disc_disc(Disc(sf[C_ROBOT_X + e], sf[C_ROBOT_Y + e], params.robot_radius), d);
    let hb = e * S_H_X;
    for (var i = hb; i < hb + su[C_N_HUMANS + e] && !hit; i++) {
        hit = geo_disc_disc(Disc(sf[C_H_X + i], sf[C_H_Y + i], params.human_radius), d);
    }
    let pb = e * S_P_X;
    for (var i = pb; i < pb + su[C_N_PLANTS + e] && !hit; i++) {
        hit = geo_disc_disc(Disc(sf[C_P_X + i], sf[C_P_Y + i], params.plant_radius), d);
    }
    for (var w = 0u; w < su[C_N_WALLS + e] && !hit; w++) {
        hit = geo_disc_rect(d, world_wall_rect(e, w));
    }
    for (var k = 0u; k < su[C_N_TABLES + e] && !hit; k++) {
        hit = geo_disc_rect(d, world_table_rect(e, k));
    }
    for (var k = 0u; k < su[C_N_LAPTOPS + e] && !hit; k++) {
        hit = geo_disc_rect(d, world_laptop_rect(e, k));
    }
    for (var b = 0u; b < su[C_N_BLOCKERS + e] && !hit; b++) {
        hit = geo_disc_rect(d, world_blocker_rect(e, b));
    }
    return hit;
}

// Rust `touches_goal`: does d touch a current goal (the robot's, a lone human's, a moving
// group's)?
fn goals_touches_goal(e: u32, d: Disc) -> bool {
    var hit = geo_disc_disc(d, Disc(sf[C_GOAL_X + e], sf[C_GOAL_Y + e], params.goal_radius));
    let hb = e * S_H_X;
    let n_lone = su[C_N_STATIC + e] + su[C_N_DYNAMIC + e];
    for (var i = hb; i < hb + n_lone && !hit; i++) {
        hit = geo_disc_disc(d, Disc(sf[C_H_GOAL_X + i], sf[C_H_GOAL_Y + i], params.human_goal_radius));
    }
    let gb = e * S_G_X;
    for (var g = gb; g < gb + su[C_N_GROUPS + e] && !hit; g++) {
        hit = su[C_G_KIND + g] == GROUP_MOVING
            && geo_disc_disc(d, Disc(sf[C_G_GOAL_X + g], sf[C_G_GOAL_Y + g], params.group_goal_radius));
    }
    return hit;
}

// Rust `sample_goal`: a goal disc of radius r free of every entity and every current goal, or
// none after PLACE_MAX_TRIES tries.
fn goals_sample_goal(e: u32, rng: ptr<function, RngStream>, r: f32) -> GoalSample {
    let area = place_sampling_box(sf[C_MAP_X + e], sf[C_MAP_Y + e]);
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
