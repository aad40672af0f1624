// requires: common/orca_world.wgsl
// requires: common/motion.wgsl
//
// Twin of `shadow_robot` and `command_from_velocity` in src/systems/shadow_robot.rs (stage
// `shadow_robot`, docs/spec.md 8.2): the reference robot behind STL and SPL drives to the robot's
// goal, every step until it collides or arrives, by the ORCA velocity of a fresh simulator that
// holds every lone human and moving group (it sees everything: `view: None`), converted to the
// robot's kinematics, then integrated like the robot (`integrate`, common/motion.wgsl). Its outcome
// (`shadow_outcome`) is in termination.wgsl.
// Same operations in the same order as the Rust file; change both in the same commit.
//
// If the ORCA lists overflow (common/orca_world.wgsl), the shadow pose and command become NaN.

// A world-frame velocity (m/s) as a robot command (v_x, v_y, ω): diff-drive drives at |v| and
// turns by the (unwrapped) heading error per step; holonomic drives v rotated into the robot
// frame. Each component is clipped to its maximum.
fn command_from_velocity(theta: f32, vx: f32, vy: f32) -> vec3<f32> {
    let v = params.robot_max_speed;
    let wmax = params.robot_max_rotation;
    let w = clamp((math_atan2(vy, vx) - theta) / params.dt, -wmax, wmax);
    if (params.holonomic != 0u) {
        let sc = math_sin_cos(theta);
        let sn = sc.x;
        let c = sc.y;
        let fx = c * vx + sn * vy;
        let fy = c * vy - sn * vx;
        return vec3<f32>(clamp(fx, -v, v), clamp(fy, -v, v), w);
    }
    return vec3<f32>(clamp(sqrt(vx * vx + vy * vy), -v, v), 0.0, w);
}

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_shadow_robot(e: u32) {
    if (su[batch.c_shadow_collided + e] != 0u || su[batch.c_shadow_reached + e] != 0u) {
        return;
    }
    let x = sf[batch.c_shadow_x + e];
    let y = sf[batch.c_shadow_y + e];
    let theta = sf[batch.c_shadow_theta + e];
    let pref = orca_world_preferred(x, y, sf[batch.c_goal_x + e], sf[batch.c_goal_y + e], params.robot_max_speed);
    let agent = orca_world_agent(e, vec2<f32>(x, y), vec2<f32>(0.0, 0.0), pref, params.human_radius);
    // The shadow robot sees everything (0.1.1 adds every entity to its simulator).
    let others = OrcaWorldOthers(ORCA_WORLD_NONE, ORCA_WORLD_NONE, false, perception_everything());
    let r = orca_world_velocity(e, agent, others);
    if (r.overflow != 0u) {
        // Not the CPU's result: make it loud.
        let nan = math_nan();
        sf[batch.c_shadow_x + e] = nan;
        sf[batch.c_shadow_y + e] = nan;
        sf[batch.c_shadow_theta + e] = nan;
        sf[batch.c_shadow_vx + e] = nan;
        sf[batch.c_shadow_vy + e] = nan;
        sf[batch.c_shadow_w + e] = nan;
        sf[batch.c_shadow_path_length + e] = nan;
        return;
    }
    let cmd = command_from_velocity(theta, r.velocity.x, r.velocity.y);
    let vx = cmd.x;
    let vy = cmd.y;
    let w = cmd.z;
    let m = integrate(params.dt, x, y, theta, vx, vy, w);
    sf[batch.c_shadow_x + e] = m.x;
    sf[batch.c_shadow_y + e] = m.y;
    sf[batch.c_shadow_theta + e] = m.theta;
    sf[batch.c_shadow_vx + e] = vx;
    sf[batch.c_shadow_vy + e] = vy;
    sf[batch.c_shadow_w + e] = w;
    sf[batch.c_shadow_path_length + e] += sqrt(vx * vx + vy * vy) * params.dt;
}
