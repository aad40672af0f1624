// requires: common/world.wgsl
//
// Twins of the public helpers of src/systems/metrics.rs that other stages use as well (`speed`,
// `command_acceleration`, `min_human_distance`, `obstacle_distances`): a stage shader cannot
// require another stage's file, so they live here. Change both in the same commit.

// The magnitude of the vector (x, y).
fn speed(x: f32, y: f32) -> f32 {
    return sqrt(x * x + y * y);
}

// This step's acceleration (m/s²) of the robot-frame linear command, valid until `metrics` stores
// the command as the previous one.
fn command_acceleration(e: u32) -> vec2<f32> {
    return vec2<f32>(
        (sf[batch.c_robot_vx + e] - sf[batch.c_m_prev_vx + e]) / params.dt,
        (sf[batch.c_robot_vy + e] - sf[batch.c_m_prev_vy + e]) / params.dt,
    );
}

// Smallest robot-human centre distance (m); +inf without humans.
fn min_human_distance(e: u32) -> f32 {
    var best = math_inf();
    for (var i = at_human(e, 0u); i < at_human(e, su[batch.c_n_humans + e]); i += batch.k_human) {
        best = min(best, speed(sf[batch.c_h_x + i] - sf[batch.c_robot_x + e], sf[batch.c_h_y + i] - sf[batch.c_robot_y + e]));
    }
    return best;
}

// Minimum and mean distance (m) from the robot centre to plants (surface), tables and walls
// (nearest point); laptops excluded, robot radius not subtracted. (+inf, NaN) without obstacles.
fn obstacle_distances(e: u32) -> vec2<f32> {
    let rx = sf[batch.c_robot_x + e];
    let ry = sf[batch.c_robot_y + e];
    var lo = math_inf();
    var sum = 0.0;
    var n = 0u;
    for (var i = at_plant(e, 0u); i < at_plant(e, su[batch.c_n_plants + e]); i += batch.k_plant) {
        let d = speed(sf[batch.c_p_x + i] - rx, sf[batch.c_p_y + i] - ry) - params.plant_radius;
        lo = min(lo, d);
        sum += d;
        n += 1u;
    }
    for (var t = 0u; t < su[batch.c_n_tables + e]; t++) {
        let d = sqrt(geo_rect_distance_sq(world_table_rect(e, t), rx, ry));
        lo = min(lo, d);
        sum += d;
        n += 1u;
    }
    for (var w = 0u; w < su[batch.c_n_walls + e]; w++) {
        let d = sqrt(geo_rect_distance_sq(world_wall_rect(e, w), rx, ry));
        lo = min(lo, d);
        sum += d;
        n += 1u;
    }
    if (n == 0u) {
        return vec2<f32>(math_inf(), math_nan());
    }
    return vec2<f32>(lo, sum / f32(n));
}
