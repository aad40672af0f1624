// requires: common/math.wgsl
//
// Twin of `robot_motion::integrate` (src/systems/robot_motion.rs), shared by the stages that move
// a robot: `robot_motion` and `shadow_robot` (a stage file cannot require another). Change both
// files in the same commit.

struct Moved {
    x: f32,
    y: f32,
    theta: f32,
    vx: f32,
    vy: f32,
}

// A pose (m, m, rad) after one step of the command, with the command's world-frame velocity.
fn integrate(dt: f32, x: f32, y: f32, theta0: f32, vx: f32, vy: f32, w: f32) -> Moved {
    let theta = math_wrap_angle(theta0 + w * dt);
    let sc = math_sin_cos(theta);
    let s = sc.x;
    let c = sc.y;
    if (vy == 0.0) {
        return Moved(x + vx * c * dt, y + vx * s * dt, theta, vx * c, vx * s);
    }
    let sc2 = math_sin_cos(theta + MATH_FRAC_PI_2);
    let s2 = sc2.x;
    let c2 = sc2.y;
    return Moved(
        x + vx * c * dt + vy * c2 * dt,
        y + vx * s * dt + vy * s2 * dt,
        theta,
        vx * c + vy * c2,
        vx * s + vy * s2,
    );
}
