// requires: common/world.wgsl
// requires: common/perception.wgsl
//
// Twin of src/systems/sfm.rs: SocNavGym 0.1.1's one-shot social force model (docs/spec.md 4.3,
// docs/spec.md orca-sfm 3.5). The velocity of a lone walker is recomputed from scratch every step
// as (f/mass)·dt, capped at the human speed, with f = w·(desired + Σ obstacle + Σ pedestrian
// forces), w = 1/√3. Only the obstacles and humans in the walker's field of view push it
// (common/perception.wgsl); the robot, when the walker avoids it this step, pushes it seen or not.
// Library file (no entry point) over the prelude's `sf`/`su`/`params`. Same operations in the
// same order as the Rust file; change both files in the same commit. SFM_W, the weight of each
// force group (1/√3), comes from the prelude (Rust `sfm::W`).

// Rust `Params`: the per-episode SFM parameters of an environment.
struct SfmParams {
    r0: f32,
    gamma: f32,
    n: f32,
    n_prime: f32,
    lambda: f32,
}

fn sfm_length(x: f32, y: f32) -> f32 {
    return sqrt(x * x + y * y);
}

// Unit vector of (x, y); zero for the zero vector.
fn sfm_unit(x: f32, y: f32) -> vec2<f32> {
    let l = sfm_length(x, y);
    if (l > 0.0) {
        return vec2<f32>(x / l, y / l);
    }
    return vec2<f32>(0.0, 0.0);
}

// Rust `Obstacles`: what the obstacles' push on a walker depends on, and the sums of
// `Obstacles::forces` (`f`: x, y and the largest exponent `top`).
struct SfmObstacles {
    pos: vec2<f32>,
    r0: f32,
    scale: f32,
    f: vec3<f32>,
}

// The `obstacle` closure of Rust `Obstacles::forces`: the push on the walker from a point
// (ox, oy) at `surface_gap` (m), exp(a − scale) with a = −gap / r0, added to `o.f`.
fn sfm_obstacle(o: ptr<function, SfmObstacles>, ox: f32, oy: f32, surface_gap: f32) {
    let u = sfm_unit((*o).pos.x - ox, (*o).pos.y - oy);
    let a = -surface_gap / (*o).r0;
    let m = math_exp(a - (*o).scale);
    (*o).f.x += m * u.x;
    (*o).f.y += m * u.y;
    (*o).f.z = max((*o).f.z, a);
}

// The `disc_gap` closure: the gap (m) between the walker's disc and the disc (ox, oy, ro).
fn sfm_disc_gap(pos: vec2<f32>, ox: f32, oy: f32, ro: f32) -> f32 {
    return sfm_length(pos.x - ox, pos.y - oy) - ro - params.human_radius;
}

// The `push` closure for a disc: from its centre, when seen.
fn sfm_push_disc(view: MaybeView, o: ptr<function, SfmObstacles>, d: Disc) {
    if (!perception_maybe_sees_disc(view, d)) {
        return;
    }
    sfm_obstacle(o, d.x, d.y, sfm_disc_gap((*o).pos, d.x, d.y, d.r));
}

// The `push` closure for a rectangle: from its nearest point, when seen.
fn sfm_push_rect(view: MaybeView, o: ptr<function, SfmObstacles>, rc: Rect) {
    if (!perception_maybe_sees_rect(view, rc)) {
        return;
    }
    let pos = (*o).pos;
    let q = geo_rect_nearest_point(rc, pos.x, pos.y);
    sfm_obstacle(o, q.x, q.y, sfm_length(pos.x - q.x, pos.y - q.y) - params.human_radius);
}

// Rust `Obstacles::forces`: the obstacle forces on the walker at `pos` of environment e,
// rescaled by exp(−scale), and the largest exponent (−f32::MAX without any obstacle).
fn sfm_obstacle_forces(e: u32, pos: vec2<f32>, r0: f32, robot: bool, view: MaybeView, scale: f32) -> vec3<f32> {
    var o = SfmObstacles(pos, r0, scale, vec3<f32>(0.0, 0.0, -0x1.fffffep127f));
    for (var k = at_plant(e, 0u); k < at_plant(e, su[batch.c_n_plants + e]); k += batch.k_plant) {
        sfm_push_disc(view, &o, Disc(sf[batch.c_p_x + k], sf[batch.c_p_y + k], params.plant_radius));
    }
    for (var w = 0u; w < su[batch.c_n_walls + e]; w++) {
        sfm_push_rect(view, &o, world_wall_rect(e, w));
    }
    for (var t = 0u; t < su[batch.c_n_tables + e]; t++) {
        sfm_push_rect(view, &o, world_table_rect(e, t));
    }
    for (var l = 0u; l < su[batch.c_n_laptops + e]; l++) {
        if (su[batch.c_l_user + at_laptop(e, l)] == NONE) {
            sfm_push_rect(view, &o, world_laptop_rect(e, l));
        }
    }
    for (var g = at_group(e, 0u); g < at_group(e, su[batch.c_n_groups + e]); g += batch.k_group) {
        if (su[batch.c_g_kind + g] == GROUP_STANDING) {
            sfm_push_disc(view, &o, perception_group_disc(g));
        }
    }
    if (robot) {
        let rx = sf[batch.c_robot_x + e];
        let ry = sf[batch.c_robot_y + e];
        sfm_obstacle(&o, rx, ry, sfm_disc_gap(pos, rx, ry, params.robot_radius));
    }
    return o.f;
}

// Rust `pedestrian_forces`: Σ f_ij over the lone humans, moving-group members and laptop users
// `view` sees (standing-group members are obstacles through their group's disc).
fn sfm_pedestrian_forces(e: u32, i: u32, sp: SfmParams, view: MaybeView) -> vec2<f32> {
    let xi = sf[batch.c_h_x + i];
    let yi = sf[batch.c_h_y + i];
    let vix = sf[batch.c_h_vx + i];
    let viy = sf[batch.c_h_vy + i];
    var fx = 0.0;
    var fy = 0.0;
    for (var j = at_human(e, 0u); j < at_human(e, su[batch.c_n_humans + e]); j += batch.k_human) {
        if (j == i || su[batch.c_h_role + j] == ROLE_STANDING_GROUP || !perception_sees_human(view, e, j)) {
            continue;
        }
        let vjx = sf[batch.c_h_vx + j];
        let vjy = sf[batch.c_h_vy + j];
        let u = sfm_unit(sf[batch.c_h_x + j] - xi, sf[batch.c_h_y + j] - yi);
        let ex = u.x;
        let ey = u.y;
        let dx = sp.lambda * (vjx - vix) + ex;
        let dy = sp.lambda * (vjy - viy) + ey;
        let d_len = sfm_length(dx, dy);
        let b = sp.gamma * d_len;
        var tx = 0.0;
        var ty = 0.0;
        if (d_len > 0.0) {
            tx = dx / d_len;
            ty = dy / d_len;
        }
        let theta = math_acos(clamp(ex * tx + ey * ty, -1.0, 1.0));
        let nx = -ey;
        let ny = ex;
        let d = sfm_length(xi - sf[batch.c_h_x + j], yi - sf[batch.c_h_y + j]);
        if (d == 0.0 && b == 0.0) {
            // Rust: two walkers at one point with one velocity exert no force (exp(-0 / 0)).
            continue;
        }
        let m = -math_exp(-d / b);
        let a1 = sp.n_prime * b * theta;
        let a2 = sp.n * b * theta;
        let k1 = math_exp(-(a1 * a1));
        let k2 = math_exp(-(a2 * a2));
        fx += m * (k1 * tx + k2 * nx);
        fy += m * (k1 * ty + k2 * ny);
    }
    return vec2<f32>(fx, fy);
}

// Rust `velocity`: the SFM velocity (m/s, world frame) of human slot `i` (global) of environment
// e; `robot`: whether it takes the robot into account this step; `view`: what it sees.
fn sfm_velocity(e: u32, i: u32, robot: bool, view: MaybeView) -> vec2<f32> {
    let sp = SfmParams(
        sf[batch.c_sfm_r0 + e],
        sf[batch.c_sfm_gamma + e],
        sf[batch.c_sfm_n + e],
        sf[batch.c_sfm_n_prime + e],
        sf[batch.c_sfm_lambda + e],
    );
    let pos = vec2<f32>(sf[batch.c_h_x + i], sf[batch.c_h_y + i]);
    let du = sfm_unit(sf[batch.c_h_goal_x + i] - pos.x, sf[batch.c_h_goal_y + i] - pos.y);
    var fdx = params.human_max_speed * du.x;
    var fdy = params.human_max_speed * du.y;
    let fo = sfm_obstacle_forces(e, pos, sp.r0, robot, view, 0.0);
    if (!(math_is_finite_bits(fo.x) && math_is_finite_bits(fo.y))) {
        // Rust `overwhelmed`: the speed limit along the forces rescaled by exp(−top).
        let u = sfm_obstacle_forces(e, pos, sp.r0, robot, view, fo.z);
        let d = sfm_unit(u.x, u.y);
        return vec2<f32>(params.human_max_speed * d.x, params.human_max_speed * d.y);
    }
    let fp = sfm_pedestrian_forces(e, i, sp, view);
    // Rust: `W * fd + W * fo + W * fp`, fd = speed · unit. Mesa's NIR optimiser reassociates a
    // constant factor into a product (`W·(s·u)` became `(W·s)·u`) and factors `a·b + a·c` into
    // `a·(b + c)`, both of which round differently. So each weight is SFM_W through a select NIR
    // cannot fold (the time step is never negative): not a constant, and three distinct values.
    let never = params.dt < 0.0;
    let w_desired = select(SFM_W, 0.0, never);
    let w_obstacles = select(SFM_W, 1.0, never);
    let w_pedestrians = select(SFM_W, 2.0, never);
    fdx = w_desired * fdx + w_obstacles * fo.x + w_pedestrians * fp.x;
    fdy = w_desired * fdy + w_obstacles * fo.y + w_pedestrians * fp.y;
    // mass 1: v = f·dt, capped at the human speed.
    let vx = fdx * params.dt;
    let vy = fdy * params.dt;
    let v = sfm_length(vx, vy);
    if (v > params.human_max_speed) {
        let k = params.human_max_speed / v;
        return vec2<f32>(vx * k, vy * k);
    }
    return vec2<f32>(vx, vy);
}
