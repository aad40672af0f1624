// requires: common/rng.wgsl
//
// Twin of src/systems/observation/ (stage `observation`, spec 5 and 9.1): the robot record, one
// 14-float record per entity (walls split into segments), the per-type counts, the interaction
// pairs, and the humans' relative-heading cache; with every option of the observation wrappers:
// the world frame, the robot's command in its record, a limited field of view and range (visible
// records compacted to the front of each block, pairs indexing them), and Gaussian noise from the
// counter-based stream of kind 7. One environment per invocation. Change both in the same commit.
//
// The device keeps each row without its entity records' one-hot floats (`obs_payload_index`;
// `src/backend/obs_payload.rs`): they follow from the per-type counts, and the host writes them
// as it reads the row back. The robot record is kept whole.
//
// On a device that stages observations (`batch.obs_staged`, `GpuDevice::stage_observations`),
// `stage_observation` writes the observation into `scratch`, slot-major (value i of environment e at
// `batch.x_obs_staged + i * n_envs + e`: `obs_put`), so that the 32 lanes of a warp storing the
// same value of their environments store 128 consecutive bytes; `rows` then moves it into the
// environment-major rows of `obs` that the host reads, a tile at a time through workgroup memory.
// Elsewhere `stage_observation` writes the rows in place and `rows` is not dispatched. `rows` is
// an entry point of the fused pass that holds the observation (`backend::wgsl::FUSED_PASSES`).

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

fn obs_humans(e: u32, block: u32) -> u32 {
    var k = 0u;
    for (var i = at_human(e, 0u); i < at_human(e, su[batch.c_n_humans + e]); i += batch.k_human) {
        let theta = sf[batch.c_h_theta + i];
        let rel = theta - fr.theta;
        let wrapped = math_wrap_angle(rel);
        let prev = sf[batch.c_h_prev_rel_theta + i];
        sf[batch.c_h_prev_rel_theta + i] = wrapped;
        let x = sf[batch.c_h_x + i];
        let y = sf[batch.c_h_y + i];
        let l = obs_local(x, y);
        if (!obs_sees(l)) {
            continue;
        }
        let at = block + k * OBS_RECORD;
        k += 1u;
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
            let sc = math_sin_cos(rel);
            let dvx = sf[batch.c_h_vx + i] - fr.vx;
            let dvy = sf[batch.c_h_vy + i] - fr.vy;
            obs_put(at + 6u, l.x);
            obs_put(at + 7u, l.y);
            obs_put(at + 8u, sc.x);
            obs_put(at + 9u, sc.y);
            obs_put(at + 11u, sqrt(dvx * dvx + dvy * dvy));
            obs_put(at + 12u, math_wrap_angle(wrapped - prev) / params.dt);
        }
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
        var p = l;
        if (fr.world) {
            p = vec2<f32>(x, y);
        }
        let sc = obs_rel_sin_cos(sf[ctheta + i]);
        obs_object_record(block + k * OBS_RECORD, p.x, p.y, sc, radius);
        k += 1u;
    }
    return k;
}

fn obs_laptops(e: u32, block: u32) -> u32 {
    let radius = obs_circumradius(params.laptop_length, params.laptop_width);
    let n = su[batch.c_n_laptops + e];
    return obs_rectangles(block, batch.c_l_x, batch.c_l_y, batch.c_l_theta, at_laptop(e, 0u), at_laptop(e, n), batch.k_laptop, radius);
}

fn obs_tables(e: u32, block: u32) -> u32 {
    let radius = obs_circumradius(params.table_length, params.table_width);
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
        var p = l;
        if (fr.world) {
            p = vec2<f32>(x, y);
        }
        let sc = obs_plant_sin_cos();
        obs_object_record(block + k * OBS_RECORD, p.x, p.y, sc, params.plant_radius);
        k += 1u;
    }
    return k;
}

// Rust `segment`: the segment centred `along` metres from the wall's left end, as record k.
// `local` and `written` are the left end and unit direction (x, y, dx, dy).
fn obs_segment(
    block: u32, k: u32, local: vec4<f32>, written: vec4<f32>, along: f32, sc: vec2<f32>,
    radius: f32,
) -> u32 {
    if (fr.partial) {
        if (!obs_within(vec2<f32>(local.x + along * local.z, local.y + along * local.w))) {
            return 0u;
        }
    }
    obs_object_record(
        block + k * OBS_RECORD, written.x + along * written.z,
        written.y + along * written.w, sc, radius,
    );
    return 1u;
}

fn obs_walls(e: u32, block: u32) -> u32 {
    let step = params.wall_segment_size;
    var k = 0u;
    for (var w = at_wall(e, 0u); w < at_wall(e, su[batch.c_n_walls + e]); w += batch.k_wall) {
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
        // `scenario::layout::segments`.
        let full_f = floor(length / step);
        let full = u32(full_f);
        let rest = length - full_f * step;
        for (var j = 0u; j < full; j++) {
            k += obs_segment(block, k, local, written, (f32(j) + 0.5) * step, sc, 0.5 * step);
        }
        if (rest > 0.0) {
            k += obs_segment(block, k, local, written, f32(full) * step + 0.5 * rest, sc, 0.5 * rest);
        }
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

// Rust `noise::add_noise`.
fn obs_noise(e: u32, counts_in: array<u32, 5>) {
    var counts = counts_in;
    let stream = rng_new(
        su[batch.c_seed_lo + e],
        su[batch.c_seed_hi + e],
        rng_stream_id(STREAM_OBS_NOISE, su[batch.c_tick + e]),
    );
    let base = stream.base;
    let rmean = params.obs_noise[2u * NOISE_ROBOT];
    let rstd = params.obs_noise[2u * NOISE_ROBOT + 1u];
    if (rmean != 0.0 || rstd != 0.0) {
        obs_perturb(6u, 2u, base, rmean, rstd);
    }
    for (var t = 0u; t < 5u; t++) {
        let mean = params.obs_noise[2u * t];
        let std_dev = params.obs_noise[2u * t + 1u];
        if (mean == 0.0 && std_dev == 0.0) {
            continue;
        }
        var records = counts[t];
        if (params.obs_padded != 0u) {
            records = obs_capacity(t);
        }
        let first = obs_offset(t);
        for (var k = 0u; k < records; k++) {
            obs_perturb(first + k * OBS_RECORD + 6u, OBS_RECORD - 6u, base, mean, std_dev);
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

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`backend::wgsl::FUSED_PASSES`, generated) calls it.
fn stage_observation(e: u32) {
    fr = obs_frame(e);
    obs_e = e;
    obs_robot_record(e);
    var counts = array<u32, 5>(0u, 0u, 0u, 0u, 0u);
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
            let at = obs_offset(t) + k * OBS_RECORD;
            for (var i = at + OBS_ONE_HOT; i < at + OBS_RECORD; i++) {
                obs_put(i, 0.0);
            }
        }
    }
    if (params.obs_noise_on != 0u) {
        obs_noise(e, counts);
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
