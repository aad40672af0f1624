// requires: common/rng.wgsl
//
// Twin of src/systems/group_motion.rs (stage `group_motion`, spec 4.4): the members of a moving
// group walk with the group's ORCA velocity (divided by the member count as in 0.1.1) plus
// Gaussian noise per member and axis; the stored centre then becomes the members' centroid.
// Standing groups never move. Change both files in the same commit.

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
        rng_stream_id(STREAM_GROUP_NOISE, su[C_TICK + e]),
    );
    let hb = e * S_H_X;
    let gb = e * S_G_X;
    for (var g = gb; g < gb + su[C_N_GROUPS + e]; g++) {
        if (su[C_G_KIND + g] != GROUP_MOVING) {
            continue;
        }
        let n = su[C_G_COUNT + g];
        var scale = 1.0;
        if (params.group_velocity_divided != 0u) {
            scale = 1.0 / f32(n);
        }
        let gvx = sf[C_G_VX + g] * scale;
        let gvy = sf[C_G_VY + g] * scale;
        let first = hb + su[C_G_FIRST + g];
        var cx = 0.0;
        var cy = 0.0;
        for (var i = first; i < first + n; i++) {
            var nx = 0.0;
            var ny = 0.0;
            if (params.replay != 0u) {
                nx = sf[C_H_NOISE_X + i];
                ny = sf[C_H_NOISE_Y + i];
            } else if (params.group_noise_std > 0.0) {
                nx = params.group_noise_std * rng_normal(&rng);
                ny = params.group_noise_std * rng_normal(&rng);
            }
            let vx = gvx + nx;
            let vy = gvy + ny;
            let speed = sqrt(vx * vx + vy * vy);
            let theta = math_atan2(vy, vx);
            let sc = math_sin_cos(theta);
            sf[C_H_SPEED + i] = speed;
            sf[C_H_THETA + i] = theta;
            sf[C_H_VX + i] = speed * sc.y;
            sf[C_H_VY + i] = speed * sc.x;
            sf[C_H_X + i] += speed * params.dt * sc.y;
            sf[C_H_Y + i] += speed * params.dt * sc.x;
            cx += sf[C_H_X + i];
            cy += sf[C_H_Y + i];
        }
        sf[C_G_X + g] = cx / f32(n);
        sf[C_G_Y + g] = cy / f32(n);
    }
}
