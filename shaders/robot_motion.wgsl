// requires: common/motion.wgsl
//
// Twin of src/systems/robot_motion.rs (stage `robot_motion`, spec 4.1 steps 2-3): scale the
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

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= N_ENVS || su[C_STEPPING + e] == 0u) {
        return;
    }
    let cmd = command(e);
    sf[C_ROBOT_VX + e] = cmd.x;
    sf[C_ROBOT_VY + e] = cmd.y;
    sf[C_ROBOT_W + e] = cmd.z;
    let m = integrate(
        params.dt,
        sf[C_ROBOT_X + e],
        sf[C_ROBOT_Y + e],
        sf[C_ROBOT_THETA + e],
        cmd.x,
        cmd.y,
        cmd.z,
    );
    sf[C_ROBOT_X + e] = m.x;
    sf[C_ROBOT_Y + e] = m.y;
    sf[C_ROBOT_THETA + e] = m.theta;
    sf[C_ROBOT_WVX + e] = m.vx;
    sf[C_ROBOT_WVY + e] = m.vy;
}
