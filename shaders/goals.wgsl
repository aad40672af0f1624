// requires: common/rng.wgsl
// requires: common/goal_sampling.wgsl
//
// Twin of src/systems/goals.rs (stage `goals`, docs/spec.md 4.1 step 8): a lone walker within reach
// of its goal (human radius + goal radius) gets a new goal; a moving group whose members are all
// within reach of the group goal (human radius + the members' own goal radius,
// `g_member_goal_radius`) gets a new group goal (and so do its members). New goals are
// rejection-sampled in the margin box by `goals_sample_goal` (common/goal_sampling.wgsl, shared with the
// social events and formation), free of every entity where it is now and of every current goal;
// after PLACE_MAX_TRIES tries the goal stays unchanged. Draws come from the step's STREAM_GOALS stream, in the Rust order.
// Same operations in the same order as the Rust file; change both files in the same commit.

fn goal_distance(ax: f32, ay: f32, bx: f32, by: f32) -> f32 {
    let dx = ax - bx;
    let dy = ay - by;
    return sqrt(dx * dx + dy * dy);
}

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_goals(e: u32) {
    // Keyed like the Rust LazyStream (which only defers the key hash to the first draw).
    var rng = rng_new(
        su[batch.c_seed_lo + e],
        su[batch.c_seed_hi + e],
        rng_stream_id(STREAM_GOALS, su[batch.c_tick + e]),
    );
    let first = su[batch.c_n_static + e];
    for (var i = at_human(e, first); i < at_human(e, first + su[batch.c_n_dynamic + e]); i += batch.k_human) {
        let reach = params.human_radius + params.human_goal_radius;
        if (su[batch.c_h_forming + i] == 0u
            && goal_distance(sf[batch.c_h_x + i], sf[batch.c_h_y + i], sf[batch.c_h_goal_x + i], sf[batch.c_h_goal_y + i]) < reach) {
            let g = goals_sample_goal(e, &rng, params.human_goal_radius);
            if (g.found) {
                sf[batch.c_h_goal_x + i] = g.disc.x;
                sf[batch.c_h_goal_y + i] = g.disc.y;
            }
        }
    }
    for (var g = at_group(e, 0u); g < at_group(e, su[batch.c_n_groups + e]); g += batch.k_group) {
        if (su[batch.c_g_kind + g] != GROUP_MOVING) {
            continue;
        }
        // Each member within reach of the group goal by its own goal radius.
        let reach = params.human_radius + sf[batch.c_g_member_goal_radius + g];
        let m0 = at_human(e, su[batch.c_g_first + g]);
        let m1 = at_human(e, su[batch.c_g_first + g] + su[batch.c_g_count + g]);
        var arrived = true;
        for (var i = m0; i < m1; i += batch.k_human) {
            if (goal_distance(sf[batch.c_h_x + i], sf[batch.c_h_y + i], sf[batch.c_g_goal_x + g], sf[batch.c_g_goal_y + g]) < reach) {
                continue;
            }
            arrived = false;
            break;
        }
        if (arrived) {
            let goal = goals_sample_goal(e, &rng, params.group_goal_radius);
            if (goal.found) {
                sf[batch.c_g_goal_x + g] = goal.disc.x;
                sf[batch.c_g_goal_y + g] = goal.disc.y;
                for (var i = m0; i < m1; i += batch.k_human) {
                    sf[batch.c_h_goal_x + i] = goal.disc.x;
                    sf[batch.c_h_goal_y + i] = goal.disc.y;
                }
            }
        }
    }
}
