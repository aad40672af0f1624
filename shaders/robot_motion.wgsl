// requires: common/motion.wgsl
//
// Twin of src/systems/robot_motion.rs (stage `robot_motion`, docs/spec.md 4.1 steps 2-3): scale the
// action to a physical command and move the robot by semi-implicit Euler (rotate first, then
// translate along the new heading). Same operations in the same order as the Rust file; change
// both in the same commit.

// The physical command (v_x, v_y in m/s, robot frame; ω in rad/s) of environment e's action.
fn command(e: u32) -> vec3<f32> {
    let v = params.robot_max_speed;
    let w = params.robot_max_rotation;
    let vx = clamp(actions[3u * e] * v, -v, v);
    var vy = 0.0;
    if (params.holonomic != 0u) {
        vy = clamp(actions[3u * e + 1u] * v, -v, v);
    }
    let wz = clamp(actions[3u * e + 2u] * w, -w, w);
    return vec3<f32>(vx, vy, wz);
}

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_robot_motion(e: u32) {
    let cmd = command(e);
    sf[batch.c_robot_vx + e] = cmd.x;
    sf[batch.c_robot_vy + e] = cmd.y;
    sf[batch.c_robot_w + e] = cmd.z;
    let m = integrate(
        params.dt,
        sf[batch.c_robot_x + e],
        sf[batch.c_robot_y + e],
        sf[batch.c_robot_theta + e],
        cmd.x,
        cmd.y,
        cmd.z,
    );
    sf[batch.c_robot_x + e] = m.x;
    sf[batch.c_robot_y + e] = m.y;
    sf[batch.c_robot_theta + e] = m.theta;
    sf[batch.c_robot_wvx + e] = m.vx;
    sf[batch.c_robot_wvy + e] = m.vy;
}
