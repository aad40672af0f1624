// requires: common/rng.wgsl
//
// Twin of src/systems/group_motion.rs (stage `group_motion`, docs/spec.md 4.4): the members of a
// moving group walk with the group's ORCA velocity (divided by the member count as in 0.1.1) plus
// Gaussian noise per member and axis; the stored centre then becomes the members' centroid.
// Standing groups never move. Change both files in the same commit.

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_group_motion(e: u32) {
    // Keyed like the Rust LazyStream (which only defers the key hash to the first draw).
    var rng = rng_new(
        su[batch.c_seed_lo + e],
        su[batch.c_seed_hi + e],
        rng_stream_id(STREAM_GROUP_NOISE, su[batch.c_tick + e]),
    );
    for (var g = at_group(e, 0u); g < at_group(e, su[batch.c_n_groups + e]); g += batch.k_group) {
        if (su[batch.c_g_kind + g] != GROUP_MOVING) {
            continue;
        }
        let n = su[batch.c_g_count + g];
        var scale = 1.0;
        if (params.group_velocity_divided != 0u) {
            scale = 1.0 / f32(n);
        }
        let gvx = sf[batch.c_g_vx + g] * scale;
        let gvy = sf[batch.c_g_vy + g] * scale;
        let first = su[batch.c_g_first + g];
        var cx = 0.0;
        var cy = 0.0;
        for (var i = at_human(e, first); i < at_human(e, first + n); i += batch.k_human) {
            var nx = 0.0;
            var ny = 0.0;
            if (params.replay != 0u) {
                nx = sf[batch.c_h_noise_x + i];
                ny = sf[batch.c_h_noise_y + i];
            } else if (params.group_noise_std > 0.0) {
                nx = params.group_noise_std * rng_normal(&rng);
                ny = params.group_noise_std * rng_normal(&rng);
            }
            let vx = gvx + nx;
            let vy = gvy + ny;
            let speed = sqrt(vx * vx + vy * vy);
            let theta = math_atan2(vy, vx);
            let sc = math_sin_cos(theta);
            sf[batch.c_h_speed + i] = speed;
            sf[batch.c_h_theta + i] = theta;
            sf[batch.c_h_vx + i] = speed * sc.y;
            sf[batch.c_h_vy + i] = speed * sc.x;
            sf[batch.c_h_x + i] += speed * params.dt * sc.y;
            sf[batch.c_h_y + i] += speed * params.dt * sc.x;
            cx += sf[batch.c_h_x + i];
            cy += sf[batch.c_h_y + i];
        }
        sf[batch.c_g_x + g] = cx / f32(n);
        sf[batch.c_g_y + g] = cy / f32(n);
    }
}
