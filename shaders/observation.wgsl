// requires: common/rng.wgsl
//
// Twin of src/systems/observation/ (stage `observation`, docs/spec.md 5 and 9.1): the robot record,
// one 14-float record per entity (walls split into segments), the per-type counts, the interaction
// pairs, and the humans' relative-heading cache; with every option of the observation wrappers:
// the world frame, the robot's command in its record, a limited field of view and range (visible
// records compacted to the front of each block, pairs indexing them), and Gaussian noise from the
// counter-based stream of kind 7. One environment per invocation. Change both in the same commit.
//
// The device keeps each row without its entity records' one-hot floats (`obs_payload_index`;
// `src/backend/obs_payload.rs`): they follow from the per-type counts, and the host writes them
// as it reads the row back. The robot record is kept whole.
//
// On a device that stages observations (`batch.obs_staged`, `GpuPaths::stage_observations`),
// `stage_observation` writes the observation into `scratch`, slot-major (value i of environment e at
// `batch.x_obs_staged + i * n_envs + e`: `obs_put`), so that the 32 lanes of a warp storing the
// same value of their environments store 128 consecutive bytes; `rows` then moves it into the
// environment-major rows of `obs` that the host reads, a tile at a time through workgroup memory.
// Elsewhere `stage_observation` writes the rows in place and `rows` is not dispatched. `rows` is
// an entry point of the fused pass that holds the observation (`pipeline::FusedPass`).
//
// On a device that writes the entity records apart (`batch.obs_records_apart`,
// `GpuPaths::records_in_lanes`), in a whole view, `stage_observation` writes the robot record,
// the counts and the pairs, and `records`, dispatched after `main` and before `rows`, writes the
// entity records a lane each (noise included). A limited sensor compacts the records it sees, so
// there the observing lane writes them in order, as on a device that does not take that path.

// Rust `Frame`: the robot pose and velocities an observation is relative to.
struct ObsFrame {
    x: f32,
    y: f32,
    theta: f32,
    sin: f32,
    cos: f32,
    vx: f32,
    vy: f32,
    // Heading subtracted from entity headings: the robot's, or 0 in the world frame.
    ref_theta: f32,
    // Indices 11 and 12 of non-human records.
    object_v: f32,
    object_w: f32,
    world: bool,
    partial: bool,
}

var<private> fr: ObsFrame;
// The environment this invocation observes.
var<private> obs_e: u32;

// Where float `i` of a row (of the robot record, or of an entity record past its one-hot
// floats, which the device does not keep) lies in the device's row of `batch.so_obs` floats.
fn obs_payload_index(i: u32) -> u32 {
    if (i < batch.obs_robot) {
        return i;
    }
    return i - OBS_ONE_HOT * (1u + (i - batch.obs_robot) / OBS_RECORD);
}

// Float `i` of this environment's observation row (never an entity record's one-hot float):
// staged (see the head of this file), or, on a device that does not stage (`batch.obs_staged`
// 0: a software one, whose barriers are slow), in its row.
fn obs_put(i: u32, v: f32) {
    let j = obs_payload_index(i);
    if (batch.obs_staged != 0u) {
        scratch[batch.x_obs_staged + j * batch.n_envs + obs_e] = bitcast<u32>(v);
    } else {
        outf[batch.co_obs + obs_e * batch.so_obs + j] = v;
    }
}

fn obs_get(i: u32) -> f32 {
    let j = obs_payload_index(i);
    if (batch.obs_staged != 0u) {
        return bitcast<f32>(scratch[batch.x_obs_staged + j * batch.n_envs + obs_e]);
    }
    return outf[batch.co_obs + obs_e * batch.so_obs + j];
}

fn obs_frame(e: u32) -> ObsFrame {
    let theta = sf[batch.c_robot_theta + e];
    let sc = math_sin_cos(theta);
    let cx = sf[batch.c_robot_vx + e];
    let cy = sf[batch.c_robot_vy + e];
    let world = params.obs_world_frame != 0u;
    var ref_theta = theta;
    var object_v = -sqrt(cx * cx + cy * cy);
    var object_w = -sf[batch.c_robot_w + e];
    if (world) {
        ref_theta = 0.0;
        object_v = 0.0;
        object_w = 0.0;
    }
    return ObsFrame(
        sf[batch.c_robot_x + e], sf[batch.c_robot_y + e], theta, sc.x, sc.y,
        sf[batch.c_robot_wvx + e], sf[batch.c_robot_wvy + e],
        ref_theta, object_v, object_w, world, params.obs_partial != 0u,
    );
}

// World point -> robot frame.
fn obs_local(x: f32, y: f32) -> vec2<f32> {
    let dx = x - fr.x;
    let dy = y - fr.y;
    return vec2<f32>(fr.cos * dx + fr.sin * dy, fr.cos * dy - fr.sin * dx);
}

// `Sensor::within`: bearing in [-fov/2, fov/2] and distance within the range, bounds inclusive.
fn obs_within(l: vec2<f32>) -> bool {
    let half_fov = 0.5 * params.obs_fov;
    let bearing = math_atan2(l.y, l.x);
    return bearing >= -half_fov && bearing <= half_fov
        && sqrt(l.x * l.x + l.y * l.y) <= params.obs_range;
}

fn obs_sees(l: vec2<f32>) -> bool {
    return !fr.partial || obs_within(l);
}

fn obs_sees_point(x: f32, y: f32) -> bool {
    if (!fr.partial) {
        return true;
    }
    return obs_within(obs_local(x, y));
}

// sin_cos(theta - ref_theta). In the world frame the Rust subtracts 0.0 (exact: theta); written
// with the frame's heading only in the robot frame.
fn obs_rel_sin_cos(theta: f32) -> vec2<f32> {
    if (fr.world) {
        return math_sin_cos(theta);
    }
    return math_sin_cos(theta - fr.ref_theta);
}

// Plants: sin_cos(0.0 - ref_theta), spelled as the exact value of the Rust difference (+0 for
// r = ±0, else -r) so that no rewrite of `0.0 - r` to `-r` (which gives -0 at r = +0) can
// change it. (Mesa 22.3.6 was seen not to make that rewrite; the guard costs nothing.)
fn obs_plant_sin_cos() -> vec2<f32> {
    if (fr.world || fr.ref_theta == 0.0) {
        return math_sin_cos(0.0);
    }
    return math_sin_cos(-fr.ref_theta);
}

// The robot record's one-hot floats (its first OBS_ONE_HOT): 1 at ONE_HOT_ROBOT, 0 elsewhere.
// Every float of a record is stored once (no zeroing pass before the values), and the entity
// records' one-hot floats not at all (the head of this file).
fn obs_robot_one_hot() {
    for (var k = 0u; k < OBS_ONE_HOT; k++) {
        obs_put(k, select(0.0, 1.0, k == ONE_HOT_ROBOT));
    }
}

fn obs_robot_record(e: u32) {
    obs_robot_one_hot();
    if (fr.world) {
        obs_put(6u, sf[batch.c_goal_x + e]);
        obs_put(7u, sf[batch.c_goal_y + e]);
        obs_put(8u, fr.x);
        obs_put(9u, fr.y);
        obs_put(10u, fr.sin);
        obs_put(11u, fr.cos);
        obs_put(12u, sf[batch.c_robot_vx + e]);
        obs_put(13u, sf[batch.c_robot_vy + e]);
        obs_put(14u, sf[batch.c_robot_w + e]);
        obs_put(15u, params.robot_radius);
        return;
    }
    let g = obs_local(sf[batch.c_goal_x + e], sf[batch.c_goal_y + e]);
    obs_put(6u, g.x);
    obs_put(7u, g.y);
    obs_put(8u, params.robot_radius);
    if (params.obs_robot_velocity != 0u) {
        obs_put(9u, sf[batch.c_robot_vx + e]);
        obs_put(10u, sf[batch.c_robot_vy + e]);
        obs_put(11u, sf[batch.c_robot_w + e]);
    }
}

// A non-human record at `at` (its one-hot floats are the host's: the head of this file).
fn obs_object_record(at: u32, px: f32, py: f32, sc: vec2<f32>, radius: f32) {
    obs_put(at + 6u, px);
    obs_put(at + 7u, py);
    obs_put(at + 8u, sc.x);
    obs_put(at + 9u, sc.y);
    obs_put(at + 10u, radius);
    obs_put(at + 11u, fr.object_v);
    obs_put(at + 12u, fr.object_w);
    obs_put(at + 13u, 0.0);
}

// 1 if the robot centre lies within the gaze cone of the human at (hx, hy), heading cos hc, sin hs.
fn obs_gaze(hx: f32, hy: f32, hc: f32, hs: f32) -> f32 {
    let dx = fr.x - hx;
    let dy = fr.y - hy;
    let bearing = math_atan2(hc * dy - hs * dx, hc * dx + hs * dy);
    let half = 0.5 * params.gaze_angle;
    if (bearing >= -half && bearing <= half) {
        return 1.0;
    }
    return 0.0;
}

// Human element `i`'s heading relative to the robot's, wrapped (`x`), stored as its cache for
// the next step, and the cache's value before (`y`).
fn obs_human_turn(i: u32) -> vec2<f32> {
    let wrapped = math_wrap_angle(sf[batch.c_h_theta + i] - fr.theta);
    let prev = sf[batch.c_h_prev_rel_theta + i];
    sf[batch.c_h_prev_rel_theta + i] = wrapped;
    return vec2<f32>(wrapped, prev);
}

// The record at `at` of human element `i` at (x, y), `l` in the robot frame, with its turn
// (`obs_human_turn`).
fn obs_human_record(at: u32, i: u32, x: f32, y: f32, l: vec2<f32>, turn: vec2<f32>) {
    let theta = sf[batch.c_h_theta + i];
    let hsc = math_sin_cos(theta);
    obs_put(at + 10u, params.human_radius);
    obs_put(at + 13u, obs_gaze(x, y, hsc.y, hsc.x));
    if (fr.world) {
        obs_put(at + 6u, x);
        obs_put(at + 7u, y);
        obs_put(at + 8u, hsc.x);
        obs_put(at + 9u, hsc.y);
        obs_put(at + 11u, sf[batch.c_h_vx + i]);
        obs_put(at + 12u, sf[batch.c_h_vy + i]);
    } else {
        let sc = math_sin_cos(theta - fr.theta);
        let dvx = sf[batch.c_h_vx + i] - fr.vx;
        let dvy = sf[batch.c_h_vy + i] - fr.vy;
        obs_put(at + 6u, l.x);
        obs_put(at + 7u, l.y);
        obs_put(at + 8u, sc.x);
        obs_put(at + 9u, sc.y);
        obs_put(at + 11u, sqrt(dvx * dvx + dvy * dvy));
        obs_put(at + 12u, math_wrap_angle(turn.x - turn.y) / params.dt);
    }
}

// The humans' records, those a limited sensor sees compacted to the front of the block at
// `block` (every human's turn is cached, seen or not); how many.
fn obs_humans(e: u32, block: u32) -> u32 {
    var k = 0u;
    for (var i = at_human(e, 0u); i < at_human(e, su[batch.c_n_humans + e]); i += batch.k_human) {
        let turn = obs_human_turn(i);
        let x = sf[batch.c_h_x + i];
        let y = sf[batch.c_h_y + i];
        let l = obs_local(x, y);
        if (!obs_sees(l)) {
            continue;
        }
        obs_human_record(block + k * OBS_RECORD, i, x, y, l, turn);
        k += 1u;
    }
    return k;
}

// Half the diagonal of a `length` x `width` rectangle (m).
fn obs_circumradius(length: f32, width: f32) -> f32 {
    return sqrt(0.25 * length * length + 0.25 * width * width);
}

// Records of the rectangles (laptops or tables) whose x, y and heading columns start at `cx`,
// `cy`, `ctheta`: the elements from `first` to `end` (excluded), `step` apart, i.e. `at_<kind>`
// of the environment's slot 0 and of its count, and `batch.k_<kind>` (twin of the Rust
// `rectangles`).
fn obs_rectangles(
    block: u32,
    cx: u32,
    cy: u32,
    ctheta: u32,
    first: u32,
    end: u32,
    step: u32,
    radius: f32,
) -> u32 {
    var k = 0u;
    for (var i = first; i < end; i += step) {
        let x = sf[cx + i];
        let y = sf[cy + i];
        let l = obs_local(x, y);
        if (!obs_sees(l)) {
            continue;
        }
        obs_rectangle_record(block + k * OBS_RECORD, x, y, l, sf[ctheta + i], radius);
        k += 1u;
    }
    return k;
}

// Where an object record puts the object at (x, y), `l` in the robot frame: there, or at (x, y)
// in the world frame.
fn obs_written(x: f32, y: f32, l: vec2<f32>) -> vec2<f32> {
    if (fr.world) {
        return vec2<f32>(x, y);
    }
    return l;
}

// The record at `at` of a rectangle at (x, y), `l` in the robot frame, heading `theta`.
fn obs_rectangle_record(at: u32, x: f32, y: f32, l: vec2<f32>, theta: f32, radius: f32) {
    let p = obs_written(x, y, l);
    obs_object_record(at, p.x, p.y, obs_rel_sin_cos(theta), radius);
}

// The record at `at` of a plant at (x, y), `l` in the robot frame.
fn obs_plant_record(at: u32, x: f32, y: f32, l: vec2<f32>) {
    let p = obs_written(x, y, l);
    obs_object_record(at, p.x, p.y, obs_plant_sin_cos(), params.plant_radius);
}

fn obs_laptop_radius() -> f32 {
    return obs_circumradius(params.laptop_length, params.laptop_width);
}

fn obs_table_radius() -> f32 {
    return obs_circumradius(params.table_length, params.table_width);
}

fn obs_laptops(e: u32, block: u32) -> u32 {
    let radius = obs_laptop_radius();
    let n = su[batch.c_n_laptops + e];
    return obs_rectangles(block, batch.c_l_x, batch.c_l_y, batch.c_l_theta, at_laptop(e, 0u), at_laptop(e, n), batch.k_laptop, radius);
}

fn obs_tables(e: u32, block: u32) -> u32 {
    let radius = obs_table_radius();
    let n = su[batch.c_n_tables + e];
    return obs_rectangles(block, batch.c_t_x, batch.c_t_y, batch.c_t_theta, at_table(e, 0u), at_table(e, n), batch.k_table, radius);
}

fn obs_plants(e: u32, block: u32) -> u32 {
    var k = 0u;
    for (var i = at_plant(e, 0u); i < at_plant(e, su[batch.c_n_plants + e]); i += batch.k_plant) {
        let x = sf[batch.c_p_x + i];
        let y = sf[batch.c_p_y + i];
        let l = obs_local(x, y);
        if (!obs_sees(l)) {
            continue;
        }
        obs_plant_record(block + k * OBS_RECORD, x, y, l);
        k += 1u;
    }
    return k;
}

// A wall as its records see it: its left end and unit direction in the robot frame (`local`:
// x, y, dx, dy) and as written (`written`: the same, or world coordinates in the world frame),
// its heading's sin and cos as written, and how it is cut into segments.
struct ObsWall {
    local: vec4<f32>,
    written: vec4<f32>,
    sc: vec2<f32>,
    cut: WallCut,
}

// `scenario::layout::segments` of a wall: `full` segments of the config's segment size, then one
// of the `rest` (m) if there is any.
struct WallCut {
    full: u32,
    rest: f32,
}

fn obs_wall_cut(w: u32) -> WallCut {
    let length = sf[batch.c_w_length + w];
    let full_f = floor(length / params.wall_segment_size);
    return WallCut(u32(full_f), length - full_f * params.wall_segment_size);
}

// Segments of a wall.
fn obs_wall_segments(cut: WallCut) -> u32 {
    return cut.full + select(0u, 1u, cut.rest > 0.0);
}

fn obs_wall(w: u32) -> ObsWall {
    let length = sf[batch.c_w_length + w];
    let wc = sf[batch.c_w_cos + w];
    let ws = sf[batch.c_w_sin + w];
    let x0 = sf[batch.c_w_x + w] - 0.5 * length * wc;
    let y0 = sf[batch.c_w_y + w] - 0.5 * length * ws;
    let l = obs_local(x0, y0);
    let dx = fr.cos * wc + fr.sin * ws;
    let dy = fr.cos * ws - fr.sin * wc;
    let local = vec4<f32>(l.x, l.y, dx, dy);
    var written = local;
    if (fr.world) {
        written = vec4<f32>(x0, y0, wc, ws);
    }
    let sc = obs_rel_sin_cos(sf[batch.c_w_theta + w]);
    return ObsWall(local, written, sc, obs_wall_cut(w));
}

// Rust `segment`: segment `j` of the wall (`obs_wall_segments`), as record `k` of the block at
// `block`, unless a limited sensor does not see it; 1 if written.
fn obs_segment(block: u32, k: u32, wall: ObsWall, j: u32) -> u32 {
    let step = params.wall_segment_size;
    var along = (f32(j) + 0.5) * step;
    var radius = 0.5 * step;
    if (j == wall.cut.full) {
        along = f32(wall.cut.full) * step + 0.5 * wall.cut.rest;
        radius = 0.5 * wall.cut.rest;
    }
    let local = wall.local;
    if (fr.partial) {
        if (!obs_within(vec2<f32>(local.x + along * local.z, local.y + along * local.w))) {
            return 0u;
        }
    }
    let written = wall.written;
    obs_object_record(
        block + k * OBS_RECORD, written.x + along * written.z,
        written.y + along * written.w, wall.sc, radius,
    );
    return 1u;
}

// The walls' records, wall by wall and segment by segment, those a limited sensor sees compacted
// to the front of the block at `block`; how many.
fn obs_walls(e: u32, block: u32) -> u32 {
    var k = 0u;
    for (var w = at_wall(e, 0u); w < at_wall(e, su[batch.c_n_walls + e]); w += batch.k_wall) {
        let wall = obs_wall(w);
        let n = obs_wall_segments(wall.cut);
        for (var j = 0u; j < n; j++) {
            k += obs_segment(block, k, wall, j);
        }
    }
    return k;
}

// How many records the walls of a whole view have: every segment of every wall.
fn obs_walls_counted(e: u32) -> u32 {
    var k = 0u;
    for (var w = at_wall(e, 0u); w < at_wall(e, su[batch.c_n_walls + e]); w += batch.k_wall) {
        k += obs_wall_segments(obs_wall_cut(w));
    }
    return k;
}

// Rust `noise::perturb` of `n` values from row index `first`.
fn obs_perturb(first: u32, n: u32, base: u32, mean: f32, std_dev: f32) {
    for (var i = first; i < first + n; i++) {
        var rng = RngStream(base, 2u * i);
        obs_put(i, obs_get(i) + rng_gauss(&rng, mean, std_dev));
    }
}

fn obs_offset(t: u32) -> u32 {
    var v = batch.obs_offset_walls;
    switch (t) {
        case 0u: { v = batch.obs_offset_humans; }
        case 1u: { v = batch.obs_offset_laptops; }
        case 2u: { v = batch.obs_offset_tables; }
        case 3u: { v = batch.obs_offset_plants; }
        default: {}
    }
    return v;
}

fn obs_capacity(t: u32) -> u32 {
    var v = batch.obs_capacity_walls;
    switch (t) {
        case 0u: { v = batch.obs_capacity_humans; }
        case 1u: { v = batch.obs_capacity_laptops; }
        case 2u: { v = batch.obs_capacity_tables; }
        case 3u: { v = batch.obs_capacity_plants; }
        default: {}
    }
    return v;
}

// The base of this step's observation-noise stream of environment `e` (Rust `noise::add_noise`).
fn obs_noise_base(e: u32) -> u32 {
    let stream = rng_new(
        su[batch.c_seed_lo + e],
        su[batch.c_seed_hi + e],
        rng_stream_id(STREAM_OBS_NOISE, su[batch.c_tick + e]),
    );
    return stream.base;
}

// Whether record `k` of entity type `t`, with `count` records present, gets noise: a present
// one, or any padding record of a padded layout (Rust `noise::add_noise`).
fn obs_noisy_record(t: u32, k: u32, count: u32) -> bool {
    let mean = params.obs_noise[2u * t];
    let std_dev = params.obs_noise[2u * t + 1u];
    return (mean != 0.0 || std_dev != 0.0) && (k < count || params.obs_padded != 0u);
}

// Noise on the floats of record `k` of entity type `t` past its one-hot floats.
fn obs_perturb_record(t: u32, k: u32, base: u32) {
    let first = obs_offset(t) + k * OBS_RECORD + OBS_ONE_HOT;
    let mean = params.obs_noise[2u * t];
    obs_perturb(first, OBS_RECORD - OBS_ONE_HOT, base, mean, params.obs_noise[2u * t + 1u]);
}

// Rust `noise::add_noise`, on the robot record and, with `records`, the entity records (where
// `records` writes those, it adds theirs).
fn obs_noise(e: u32, counts_in: array<u32, 5>, records: bool) {
    var counts = counts_in;
    let base = obs_noise_base(e);
    let rmean = params.obs_noise[2u * NOISE_ROBOT];
    let rstd = params.obs_noise[2u * NOISE_ROBOT + 1u];
    if (rmean != 0.0 || rstd != 0.0) {
        obs_perturb(6u, 2u, base, rmean, rstd);
    }
    if (!records) {
        return;
    }
    for (var t = 0u; t < 5u; t++) {
        for (var k = 0u; k < obs_capacity(t); k++) {
            if (obs_noisy_record(t, k, counts[t])) {
                obs_perturb_record(t, k, base);
            }
        }
    }
}

// How many of the human slots [lo, hi) of environment e the sensor sees.
fn obs_humans_seen(e: u32, lo: u32, hi: u32) -> u32 {
    var n = 0u;
    for (var k = lo; k < hi; k++) {
        let i = at_human(e, k);
        if (obs_sees_point(sf[batch.c_h_x + i], sf[batch.c_h_y + i])) {
            n += 1u;
        }
    }
    return n;
}

fn obs_laptops_seen(e: u32, to: u32) -> u32 {
    var n = 0u;
    for (var k = 0u; k < to; k++) {
        let i = at_laptop(e, k);
        if (obs_sees_point(sf[batch.c_l_x + i], sf[batch.c_l_y + i])) {
            n += 1u;
        }
    }
    return n;
}

fn obs_human_human(e: u32) -> u32 {
    let out = batch.co_hh_pairs + e * batch.so_hh_pairs;
    var n = 0u;
    var slot = 0u;
    var seen = 0u;
    for (var g = at_group(e, 0u); g < at_group(e, su[batch.c_n_groups + e]); g += batch.k_group) {
        let first = su[batch.c_g_first + g];
        let end = first + su[batch.c_g_count + g];
        var start = first;
        var stop = end;
        if (fr.partial) {
            start = seen + obs_humans_seen(e, slot, first);
            seen = start + obs_humans_seen(e, first, end);
            stop = seen;
        }
        slot = end;
        for (var a = start; a < stop; a++) {
            for (var b = a + 1u; b < stop; b++) {
                outu[out + 2u * n] = a;
                outu[out + 2u * n + 1u] = b;
                outu[out + 2u * n + 2u] = b;
                outu[out + 2u * n + 3u] = a;
                n += 2u;
            }
        }
    }
    for (var k = 2u * n; k < batch.so_hh_pairs; k++) {
        outu[out + k] = 0u;
    }
    return n;
}

fn obs_human_laptop(e: u32) -> u32 {
    let out = batch.co_hl_pairs + e * batch.so_hl_pairs;
    var n = 0u;
    for (var u = at_laptop_user(e, 0u); u < at_laptop_user(e, su[batch.c_n_laptop_users + e]); u += batch.k_laptop_user) {
        var h = su[batch.c_lu_human + u];
        var l = su[batch.c_lu_laptop + u];
        if (fr.partial) {
            let hi = at_human(e, h);
            let li = at_laptop(e, l);
            if (!obs_sees_point(sf[batch.c_h_x + hi], sf[batch.c_h_y + hi])
                || !obs_sees_point(sf[batch.c_l_x + li], sf[batch.c_l_y + li])) {
                continue;
            }
            h = obs_humans_seen(e, 0u, h);
            l = obs_laptops_seen(e, l);
        }
        outu[out + 2u * n] = h;
        outu[out + 2u * n + 1u] = l;
        n += 1u;
    }
    for (var k = 2u * n; k < batch.so_hl_pairs; k++) {
        outu[out + k] = 0u;
    }
    return n;
}

// A padding record at `at`: its floats past the one-hot ones, zero.
fn obs_zero_record(at: u32) {
    for (var i = at + OBS_ONE_HOT; i < at + OBS_RECORD; i++) {
        obs_put(i, 0.0);
    }
}

// Whether `records` writes the entity records, a lane each, rather than the observing lane: on
// a device that takes that path (`batch.obs_records_apart`, `GpuPaths::records_in_lanes`) in a
// whole view, where entity k of a type (segment k of the walls) is its record k (a limited sensor
// compacts the records it sees, so there one lane writes them in order).
fn obs_records_apart() -> bool {
    return batch.obs_records_apart != 0u && !fr.partial;
}

// How many entities of type `t` environment `e` has (walls: segments): its records in a whole
// view.
fn obs_present(e: u32, t: u32) -> u32 {
    var n = 0u;
    switch (t) {
        case 0u: { n = su[batch.c_n_humans + e]; }
        case 1u: { n = su[batch.c_n_laptops + e]; }
        case 2u: { n = su[batch.c_n_tables + e]; }
        case 3u: { n = su[batch.c_n_plants + e]; }
        default: { n = obs_walls_counted(e); }
    }
    return n;
}

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_observation(e: u32) {
    fr = obs_frame(e);
    obs_e = e;
    obs_robot_record(e);
    var counts = array<u32, 5>(0u, 0u, 0u, 0u, 0u);
    let apart = obs_records_apart();
    if (apart) {
        for (var t = 0u; t < 5u; t++) {
            if (obs_capacity(t) > 0u) {
                counts[t] = obs_present(e, t);
            }
        }
    } else {
        counts[0] = obs_humans(e, batch.obs_offset_humans);
        counts[1] = obs_laptops(e, batch.obs_offset_laptops);
        counts[2] = obs_tables(e, batch.obs_offset_tables);
        counts[3] = obs_plants(e, batch.obs_offset_plants);
        if (batch.obs_capacity_walls > 0u) {
            counts[4] = obs_walls(e, batch.obs_offset_walls);
        }
        // The padding records past the counts: their floats past the one-hot ones.
        for (var t = 0u; t < 5u; t++) {
            for (var k = counts[t]; k < obs_capacity(t); k++) {
                obs_zero_record(obs_offset(t) + k * OBS_RECORD);
            }
        }
    }
    if (params.obs_noise_on != 0u) {
        obs_noise(e, counts, !apart);
    }
    for (var t = 0u; t < 5u; t++) {
        outu[batch.co_obs_count + e * batch.so_obs_count + t] = counts[t];
    }
    let pc = batch.co_pair_count + e * batch.so_pair_count;
    outu[pc] = obs_human_human(e);
    outu[pc + 1u] = obs_human_laptop(e);
}

// A tile of the staged observation: OBS_TILE values of WORKGROUP_SIZE environments, value f of
// the workgroup's environment j at `f * (WORKGROUP_SIZE + 1) + j` (the extra column keeps the
// reads of `rows`' second half, a lane per value, on distinct memory banks).
var<workgroup> obs_tile: array<u32, OBS_TILE * (WORKGROUP_SIZE + 1u)>;

// The staged observation into the rows of `obs`, for the environments that stepped: workgroup
// (x, y) moves values [y * OBS_TILE, +OBS_TILE) of environments [x * WORKGROUP_SIZE, +WORKGROUP_SIZE).
// It reads with consecutive lanes on consecutive environments (one value of each) and writes with
// consecutive lanes on consecutive values of a row, so both sides coalesce. The words are moved,
// never computed on, so the rows hold the bits `stage_observation` staged.
@compute @workgroup_size(WORKGROUP_SIZE)
fn rows(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let e0 = wg.x * WORKGROUP_SIZE;
    let f0 = wg.y * OBS_TILE;
    let values = min(OBS_TILE, batch.so_obs - min(f0, batch.so_obs));
    let pitch = WORKGROUP_SIZE + 1u;
    if (e0 + lane < batch.n_envs) {
        for (var f = 0u; f < values; f++) {
            obs_tile[f * pitch + lane] = scratch[batch.x_obs_staged + (f0 + f) * batch.n_envs + e0 + lane];
        }
    }
    workgroupBarrier();
    // Lane `lane` writes value `lane % OBS_TILE` of every (WORKGROUP_SIZE / OBS_TILE)-th
    // environment from `lane / OBS_TILE` (divisions by a power of two).
    let f = lane % OBS_TILE;
    if (f >= values) {
        return;
    }
    for (var j = lane / OBS_TILE; j < WORKGROUP_SIZE; j += WORKGROUP_SIZE / OBS_TILE) {
        let e = e0 + j;
        if (e < batch.n_envs && su[batch.c_stepping + e] != 0u) {
            outf[batch.co_obs + e * batch.so_obs + f0 + f] = bitcast<f32>(obs_tile[f * pitch + j]);
        }
    }
}

// The entity records of a whole view, a lane each (`obs_records_apart`): lane `lane` of
// workgroup (x, y) writes entity record y of the row of environment x * WORKGROUP_SIZE + lane (of
// the records of every type, in row order), for the environments that stepped, after `main` has
// written the robot record, the counts and the pairs. Record k of a type is its entity k (the
// walls: segment k in `obs_walls`' order), or padding past the last one; with its noise
// (`obs_noise` leaves the entity records to this). The 32 lanes of a warp write the same record
// of 32 environments, so their stores coalesce where the observation is staged, and a record
// waits on no other: the observing lane's loops over every record (exp2: 49, 40 of them wall
// segments), serial, become a lane each.
@compute @workgroup_size(WORKGROUP_SIZE)
fn records(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let e = wg.x * WORKGROUP_SIZE + lane;
    if (e >= batch.n_envs || su[batch.c_stepping + e] == 0u) {
        return;
    }
    fr = obs_frame(e);
    obs_e = e;
    if (!obs_records_apart()) {
        return;
    }
    // Record y's type and its index among that type's records.
    var t = 0u;
    var k = wg.y;
    while (t < 4u && k >= obs_capacity(t)) {
        k -= obs_capacity(t);
        t += 1u;
    }
    let at = obs_offset(t) + k * OBS_RECORD;
    let present = obs_present(e, t);
    if (k >= present) {
        obs_zero_record(at);
    } else {
        switch (t) {
            case 0u: { obs_human_record_of(e, k, at); }
            case 1u: {
                let i = at_laptop(e, k);
                let radius = obs_laptop_radius();
                obs_rectangle_of(at, i, batch.c_l_x, batch.c_l_y, batch.c_l_theta, radius);
            }
            case 2u: {
                let i = at_table(e, k);
                let radius = obs_table_radius();
                obs_rectangle_of(at, i, batch.c_t_x, batch.c_t_y, batch.c_t_theta, radius);
            }
            case 3u: { obs_plant_of(at, at_plant(e, k)); }
            default: { obs_segment_of(e, k); }
        }
    }
    if (params.obs_noise_on != 0u && obs_noisy_record(t, k, present)) {
        obs_perturb_record(t, k, obs_noise_base(e));
    }
}

// Human slot `k`'s record at `at` in a whole view, its turn cached.
fn obs_human_record_of(e: u32, k: u32, at: u32) {
    let i = at_human(e, k);
    let turn = obs_human_turn(i);
    let x = sf[batch.c_h_x + i];
    let y = sf[batch.c_h_y + i];
    obs_human_record(at, i, x, y, obs_local(x, y), turn);
}

// The record at `at` of the rectangle element `i` of columns `cx`, `cy`, `ctheta`.
fn obs_rectangle_of(at: u32, i: u32, cx: u32, cy: u32, ctheta: u32, radius: f32) {
    let x = sf[cx + i];
    let y = sf[cy + i];
    obs_rectangle_record(at, x, y, obs_local(x, y), sf[ctheta + i], radius);
}

fn obs_plant_of(at: u32, i: u32) {
    let x = sf[batch.c_p_x + i];
    let y = sf[batch.c_p_y + i];
    obs_plant_record(at, x, y, obs_local(x, y));
}

// Wall segment `k` of environment `e` (of every wall's segments in order; `k` below their count)
// as its record k.
fn obs_segment_of(e: u32, k: u32) {
    var first = 0u;
    for (var w = at_wall(e, 0u); w < at_wall(e, su[batch.c_n_walls + e]); w += batch.k_wall) {
        let n = obs_wall_segments(obs_wall_cut(w));
        if (k < first + n) {
            _ = obs_segment(batch.obs_offset_walls, k, obs_wall(w), k - first);
            return;
        }
        first += n;
    }
}
