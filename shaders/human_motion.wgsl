// requires: common/rng.wgsl
// requires: common/orca_world.wgsl
// requires: common/sfm.wgsl
//
// Twin of src/systems/human_motion.rs (stage `human_motion`, docs/spec.md 4.1 step 6, 4.2-4.3):
// each lone walker, in slot order, chooses a velocity with its policy (ORCA,
// common/orca_world.wgsl, or SFM, common/sfm.wgsl) and moves at once, so later walkers see it where
// it now is. Speeds below the threshold become 0 (except for walkers heading to a forming crowd);
// the heading always follows the velocity. Whether a walker takes the robot into account is drawn
// every step with `prob_to_avoid_robot` from the step's STREAM_AVOID_ROBOT stream (nothing drawn
// when it is 0). Both policies see only what lies in the walker's field of view
// (common/perception.wgsl). Same operations in the same order as the Rust file; change both files
// in the same commit.
//
// If the ORCA lists overflow (common/orca_world.wgsl), the walker's velocity is NaN and so
// become its speed, heading and position: never a silently different value.

// Rust `orca_velocity`: the ORCA velocity (m/s) of lone walker `i` (global slot) of environment
// e, at rest (or at its velocity) wanting to go to its goal at the human speed, among the other
// lone humans, the moving groups and, if it avoids it, the robot, of which it meets what `view`
// sees.
fn orca_velocity(e: u32, i: u32, avoid_robot: bool, view: MaybeView) -> vec2<f32> {
    let x = sf[batch.c_h_x + i];
    let y = sf[batch.c_h_y + i];
    let pref = orca_world_preferred(x, y, sf[batch.c_h_goal_x + i], sf[batch.c_h_goal_y + i], params.human_max_speed);
    var vel = vec2<f32>(0.0, 0.0);
    if (params.orca_actual_velocity != 0u) {
        vel = vec2<f32>(sf[batch.c_h_vx + i], sf[batch.c_h_vy + i]);
    }
    let agent = orca_world_agent(e, vec2<f32>(x, y), vel, pref, params.human_radius);
    let others = OrcaWorldOthers(i, ORCA_WORLD_NONE, avoid_robot, view);
    return orca_world_velocity(e, agent, others).velocity;
}

// Rust `walk`: apply velocity (vx, vy) (m/s) to human `i`: threshold the speed, turn to the
// velocity, move.
fn walk(i: u32, vx: f32, vy: f32) {
    var speed = sqrt(vx * vx + vy * vy);
    if (speed < params.speed_threshold && su[batch.c_h_forming + i] != FORMING_CROWD) {
        speed = 0.0;
    }
    let theta = math_atan2(vy, vx);
    let sc = math_sin_cos(theta);
    sf[batch.c_h_speed + i] = speed;
    sf[batch.c_h_theta + i] = theta;
    sf[batch.c_h_vx + i] = speed * sc.y;
    sf[batch.c_h_vy + i] = speed * sc.x;
    sf[batch.c_h_x + i] += speed * params.dt * sc.y;
    sf[batch.c_h_y + i] += speed * params.dt * sc.x;
}

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_human_motion(e: u32) {
    // Keyed like the Rust LazyStream (which only defers the key hash to the first draw).
    var rng = rng_new(
        su[batch.c_seed_lo + e],
        su[batch.c_seed_hi + e],
        rng_stream_id(STREAM_AVOID_ROBOT, su[batch.c_tick + e]),
    );
    let first = su[batch.c_n_static + e];
    for (var i = at_human(e, first); i < at_human(e, first + su[batch.c_n_dynamic + e]); i += batch.k_human) {
        // Nothing to draw when no walker avoids the robot (every paper config).
        let avoid_robot = params.prob_avoid_robot > 0.0 && rng_chance(&rng, params.prob_avoid_robot);
        let view = perception_view_of_human(i);
        var v: vec2<f32>;
        if (su[batch.c_h_policy + i] == POLICY_ORCA) {
            v = orca_velocity(e, i, avoid_robot, view);
        } else {
            v = sfm_velocity(e, i, avoid_robot, view);
        }
        walk(i, v.x, v.y);
    }
}
