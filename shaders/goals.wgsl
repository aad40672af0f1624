// requires: common/rng.wgsl
// requires: common/goals.wgsl
//
// Twin of src/systems/goals.rs (stage `goals`, spec 4.1 step 8): a lone walker within reach of
// its goal (human radius + goal radius) gets a new goal; a moving group whose members are all
// within reach of the group goal (human radius + the members' own goal radius,
// `g_member_goal_radius`) gets a new group goal (and so do its members). New goals are
// rejection-sampled in the margin box by `goals_sample_goal` (common/goals.wgsl, shared with the
// social events and formation), free of every entity where it is now and of every current goal;
// after PLACE_MAX_TRIES tries the goal stays unchanged. Draws come from the step's STREAM_GOALS stream, in the Rust order.
// Same operations in the same order as the Rust file; change both files in the same commit.

fn goal_distance(ax: f32, ay: f32, bx: f32, by: f32) -> f32 {
    let dx = ax - bx;
    let dy = ay - by;
    return sqrt(dx * dx + dy * dy);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= N_ENVS || su[C_STEPPING + e] == 0u) {
        return;
    }
    // Keyed like the Rust LazyStream (which only defers the key hash to the first draw).
    var rng = rng_new(
        params.seed_lo,
        params.seed_hi,
        e,
        su[C_EPISODE + e],
        rng_stream_id(STREAM_GOALS, su[C_TICK + e]),
    );
    let hb = e * S_H_X;
    let first = hb + su[C_N_STATIC + e];
    for (var i = first; i < first + su[C_N_DYNAMIC + e]; i++) {
        let reach = params.human_radius + params.human_goal_radius;
        if (su[C_H_FORMING + i] == 0u
            && goal_distance(sf[C_H_X + i], sf[C_H_Y + i], sf[C_H_GOAL_X + i], sf[C_H_GOAL_Y + i]) < reach) {
            let g = goals_sample_goal(e, &rng, params.human_goal_radius);
            if (g.found) {
                sf[C_H_GOAL_X + i] = g.disc.x;
                sf[C_H_GOAL_Y + i] = g.disc.y;
            }
        }
    }
    let gb = e * S_G_X;
    for (var g = gb; g < gb + su[C_N_GROUPS + e]; g++) {
        if (su[C_G_KIND + g] != GROUP_MOVING) {
            continue;
        }
        // Each member within reach of the group goal by its own goal radius.
        let reach = params.human_radius + sf[C_G_MEMBER_GOAL_RADIUS + g];
        let m0 = hb + su[C_G_FIRST + g];
        let m1 = hb + su[C_G_FIRST + g] + su[C_G_COUNT + g];
        var arrived = true;
        for (var i = m0; i < m1; i++) {
            if (goal_distance(sf[C_H_X + i], sf[C_H_Y + i], sf[C_G_GOAL_X + g], sf[C_G_GOAL_Y + g]) < reach) {
                continue;
            }
            arrived = false;
            break;
        }
        if (arrived) {
            let goal = goals_sample_goal(e, &rng, params.group_goal_radius);
            if (goal.found) {
                sf[C_G_GOAL_X + g] = goal.disc.x;
                sf[C_G_GOAL_Y + g] = goal.disc.y;
                for (var i = m0; i < m1; i++) {
                    sf[C_H_GOAL_X + i] = goal.disc.x;
                    sf[C_H_GOAL_Y + i] = goal.disc.y;
                }
            }
        }
    }
}
