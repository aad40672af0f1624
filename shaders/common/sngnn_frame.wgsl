// requires: common/math.wgsl
//
// Twin of src/sngnn/frame.rs and src/sngnn/history/write.rs: the SNGNN input frame of one
// environment (docs/spec.md 7.2) pushed into its frame history in the state's columns, and the
// robot-frame poses kept for the next step's velocities. Needs the SNGNN prelude
// (`backend::wgsl::sngnn_prelude`) and the history's sizes in the batch layout (`batch.sn_frames`,
// `batch.sn_frame_people`, ...). Same operations in the same order as the Rust, so that lavapipe computes the CPU's bits. Change both in the same commit.
//
// The SNGNN prelude defines frame.rs's constants from their Rust values: SN_ADVANCE_SCALE,
// SN_MAX_ADVANCE, SN_ROTATION_SCALE, SN_MAX_ROTATION and SN_FRAME_PERIOD (s).

// frame::RobotPose: a robot pose (m, m, rad; world) with the cos and sin of its heading.
struct SnRobot {
    x: f32,
    y: f32,
    theta: f32,
    c: f32,
    s: f32,
}

// An entity's robot-frame pose (m, m; rad wrapped to (-pi, pi]): frame::Seen.
struct SnSeen {
    x: f32,
    y: f32,
    theta: f32,
}

fn sn_robot(x: f32, y: f32, theta: f32) -> SnRobot {
    let sc = math_sin_cos(theta);
    return SnRobot(x, y, theta, sc.y, sc.x);
}

fn sn_robot_of(e: u32) -> SnRobot {
    return sn_robot(sf[batch.c_robot_x + e], sf[batch.c_robot_y + e], sf[batch.c_robot_theta + e]);
}

// World point (m) -> robot frame (x forward, y left).
fn sn_local(r: SnRobot, x: f32, y: f32) -> vec2<f32> {
    let dx = x - r.x;
    let dy = y - r.y;
    return vec2<f32>(r.c * dx + r.s * dy, r.c * dy - r.s * dx);
}

// World point (m) -> SNGNN axes (x right, y ahead): (-y_r, x_r).
fn sn_axes(r: SnRobot, x: f32, y: f32) -> vec2<f32> {
    let l = sn_local(r, x, y);
    return vec2<f32>(-l.y, l.x);
}

fn sn_seen(r: SnRobot, x: f32, y: f32, theta: f32) -> SnSeen {
    let l = sn_local(r, x, y);
    return SnSeen(l.x, l.y, math_wrap_angle(theta - r.theta));
}

// ---- history columns (history/view.rs layout: ring slot f of env e is its frame slot f; the
// frame's people are its frame_person slots f * batch.sn_frame_people + j, and likewise its
// objects and links) ----

// The frame columns' element of ring slot `slot` of environment e.
fn sn_frame_row(e: u32, slot: u32) -> u32 {
    return at_frame(e, slot);
}

// The ring slot of the frame taken `age` non-terminal steps ago (age < count).
fn sn_slot_of_age(e: u32, age: u32) -> u32 {
    return (su[batch.c_sn_newest + at_sngnn(e, 0u)] + batch.sn_frames - age) % batch.sn_frames;
}

// history::write::clear_slot: every row of ring slot `slot` zero.
fn sn_clear_slot(e: u32, slot: u32) {
    let f = sn_frame_row(e, slot);
    su[batch.c_sf_tick + f] = 0u;
    sf[batch.c_sf_robot_x + f] = 0.0;
    sf[batch.c_sf_robot_y + f] = 0.0;
    sf[batch.c_sf_robot_theta + f] = 0.0;
    sf[batch.c_sf_goal_x + f] = 0.0;
    sf[batch.c_sf_goal_y + f] = 0.0;
    sf[batch.c_sf_advance + f] = 0.0;
    sf[batch.c_sf_lateral + f] = 0.0;
    sf[batch.c_sf_rotation + f] = 0.0;
    su[batch.c_sf_n_people + f] = 0u;
    su[batch.c_sf_n_objects + f] = 0u;
    su[batch.c_sf_n_links + f] = 0u;
    for (var i = at_frame_person(e, slot * batch.sn_frame_people); i < at_frame_person(e, (slot + 1u) * batch.sn_frame_people); i += batch.k_frame_person) {
        su[batch.c_fp_id + i] = 0u;
        sf[batch.c_fp_x + i] = 0.0;
        sf[batch.c_fp_y + i] = 0.0;
        sf[batch.c_fp_a + i] = 0.0;
        sf[batch.c_fp_vx + i] = 0.0;
        sf[batch.c_fp_vy + i] = 0.0;
        sf[batch.c_fp_va + i] = 0.0;
    }
    for (var i = at_frame_object(e, slot * batch.sn_frame_objects); i < at_frame_object(e, (slot + 1u) * batch.sn_frame_objects); i += batch.k_frame_object) {
        su[batch.c_fo_id + i] = 0u;
        sf[batch.c_fo_x + i] = 0.0;
        sf[batch.c_fo_y + i] = 0.0;
        sf[batch.c_fo_a + i] = 0.0;
        sf[batch.c_fo_vx + i] = 0.0;
        sf[batch.c_fo_vy + i] = 0.0;
        sf[batch.c_fo_va + i] = 0.0;
        sf[batch.c_fo_size_x + i] = 0.0;
        sf[batch.c_fo_size_y + i] = 0.0;
    }
    for (var i = at_frame_link(e, slot * batch.sn_frame_links); i < at_frame_link(e, (slot + 1u) * batch.sn_frame_links); i += batch.k_frame_link) {
        su[batch.c_fl_src + i] = 0u;
        su[batch.c_fl_dst + i] = 0u;
    }
}

// history::write::begin_frame: a new newest frame (the ring drops the oldest); returns its slot.
fn sn_begin_frame(e: u32, tick: u32, robot: SnRobot, goal: vec2<f32>, command: vec3<f32>) -> u32 {
    // The environment's element of the history's counters (their kind has one slot).
    let hist = at_sngnn(e, 0u);
    let count = su[batch.c_sn_frame_count + hist];
    var slot = 0u;
    if (count != 0u) {
        slot = (su[batch.c_sn_newest + hist] + 1u) % batch.sn_frames;
    }
    sn_clear_slot(e, slot);
    su[batch.c_sn_newest + hist] = slot;
    su[batch.c_sn_frame_count + hist] = min(count + 1u, batch.sn_frames);
    let f = sn_frame_row(e, slot);
    su[batch.c_sf_tick + f] = tick;
    sf[batch.c_sf_robot_x + f] = robot.x;
    sf[batch.c_sf_robot_y + f] = robot.y;
    sf[batch.c_sf_robot_theta + f] = robot.theta;
    sf[batch.c_sf_goal_x + f] = goal.x;
    sf[batch.c_sf_goal_y + f] = goal.y;
    sf[batch.c_sf_advance + f] = command.x;
    sf[batch.c_sf_lateral + f] = command.y;
    sf[batch.c_sf_rotation + f] = command.z;
    return slot;
}

// Index of entity `id`'s previous pose (ids 1..=batch.sn_entities; the CPU panics outside, the device
// clamps so that it never writes out of the environment's rows).
fn sn_prev_index(e: u32, id: u32) -> u32 {
    return at_sngnn_entity(e, clamp(id, 1u, batch.sn_entities) - 1u);
}

fn sn_previous(e: u32, id: u32) -> SnSeen {
    let i = sn_prev_index(e, id);
    return SnSeen(sf[batch.c_sn_prev_x + i], sf[batch.c_sn_prev_y + i], sf[batch.c_sn_prev_theta + i]);
}

fn sn_remember(e: u32, id: u32, seen: SnSeen) {
    let i = sn_prev_index(e, id);
    sf[batch.c_sn_prev_x + i] = seen.x;
    sf[batch.c_sn_prev_y + i] = seen.y;
    sf[batch.c_sn_prev_theta + i] = seen.theta;
}

// Seen::entry's pose fields of a frame record: x, y, a, vx, vy, va (SNGNN axes; per 0.2 s).
fn sn_entry(now: SnSeen, before: SnSeen, period_steps: f32) -> array<f32, 6> {
    return array<f32, 6>(
        -now.y,
        now.x,
        -(MATH_FRAC_PI_2 + now.theta),
        (before.x - now.x) / period_steps,
        (before.y - now.y) / period_steps,
        (before.theta - now.theta) / period_steps,
    );
}

// history::write::push_person (a full frame drops the person; the CPU panics).
fn sn_push_person(e: u32, slot: u32, id: u32, v: array<f32, 6>) {
    let f = sn_frame_row(e, slot);
    let j = su[batch.c_sf_n_people + f];
    if (j >= batch.sn_frame_people) {
        return;
    }
    let i = at_frame_person(e, slot * batch.sn_frame_people + j);
    su[batch.c_fp_id + i] = id;
    sf[batch.c_fp_x + i] = v[0];
    sf[batch.c_fp_y + i] = v[1];
    sf[batch.c_fp_a + i] = v[2];
    sf[batch.c_fp_vx + i] = v[3];
    sf[batch.c_fp_vy + i] = v[4];
    sf[batch.c_fp_va + i] = v[5];
    su[batch.c_sf_n_people + f] = j + 1u;
}

// history::write::push_object.
fn sn_push_object(e: u32, slot: u32, id: u32, v: array<f32, 6>, size: vec2<f32>) {
    let f = sn_frame_row(e, slot);
    let j = su[batch.c_sf_n_objects + f];
    if (j >= batch.sn_frame_objects) {
        return;
    }
    let i = at_frame_object(e, slot * batch.sn_frame_objects + j);
    su[batch.c_fo_id + i] = id;
    sf[batch.c_fo_x + i] = v[0];
    sf[batch.c_fo_y + i] = v[1];
    sf[batch.c_fo_a + i] = v[2];
    sf[batch.c_fo_vx + i] = v[3];
    sf[batch.c_fo_vy + i] = v[4];
    sf[batch.c_fo_va + i] = v[5];
    sf[batch.c_fo_size_x + i] = size.x;
    sf[batch.c_fo_size_y + i] = size.y;
    su[batch.c_sf_n_objects + f] = j + 1u;
}

// history::write::push_link.
fn sn_push_link(e: u32, slot: u32, src: u32, dst: u32) {
    let f = sn_frame_row(e, slot);
    let j = su[batch.c_sf_n_links + f];
    if (j >= batch.sn_frame_links) {
        return;
    }
    let i = at_frame_link(e, slot * batch.sn_frame_links + j);
    su[batch.c_fl_src + i] = src;
    su[batch.c_fl_dst + i] = dst;
    su[batch.c_sf_n_links + f] = j + 1u;
}

// frame::command: advance, lateral advance, rotation in SNGNN units.
fn sn_command(e: u32) -> vec3<f32> {
    var lateral = 0.0;
    if (params.holonomic != 0u) {
        lateral = min(SN_ADVANCE_SCALE * sf[batch.c_robot_vy + e], SN_MAX_ADVANCE);
    }
    let advance = min(SN_ADVANCE_SCALE * sf[batch.c_robot_vx + e], SN_MAX_ADVANCE);
    let rotation = clamp(SN_ROTATION_SCALE * sf[batch.c_robot_w + e], -SN_MAX_ROTATION, SN_MAX_ROTATION);
    return vec3<f32>(advance, lateral, rotation);
}

// frame::push_people: every human in slot order, remembering each pose.
fn sn_push_people(e: u32, slot: u32, robot: SnRobot, period_steps: f32) {
    for (var i = at_human(e, 0u); i < at_human(e, su[batch.c_n_humans + e]); i += batch.k_human) {
        let id = su[batch.c_h_id + i];
        let now = sn_seen(robot, sf[batch.c_h_x + i], sf[batch.c_h_y + i], sf[batch.c_h_theta + i]);
        let entry = sn_entry(now, sn_previous(e, id), period_steps);
        sn_remember(e, id, now);
        sn_push_person(e, slot, id, entry);
    }
}

// frame::push_objects: laptops, plants (2r x 2r), tables.
fn sn_push_objects(e: u32, slot: u32, robot: SnRobot, period_steps: f32) {
    for (var i = at_laptop(e, 0u); i < at_laptop(e, su[batch.c_n_laptops + e]); i += batch.k_laptop) {
        let id = su[batch.c_l_id + i];
        let now = sn_seen(robot, sf[batch.c_l_x + i], sf[batch.c_l_y + i], sf[batch.c_l_theta + i]);
        let size = vec2<f32>(params.laptop_length, params.laptop_width);
        let entry = sn_entry(now, sn_previous(e, id), period_steps);
        sn_remember(e, id, now);
        sn_push_object(e, slot, id, entry, size);
    }
    let diameter = 2.0 * params.plant_radius;
    for (var i = at_plant(e, 0u); i < at_plant(e, su[batch.c_n_plants + e]); i += batch.k_plant) {
        let id = su[batch.c_p_id + i];
        let now = sn_seen(robot, sf[batch.c_p_x + i], sf[batch.c_p_y + i], 0.0);
        let size = vec2<f32>(diameter, diameter);
        let entry = sn_entry(now, sn_previous(e, id), period_steps);
        sn_remember(e, id, now);
        sn_push_object(e, slot, id, entry, size);
    }
    for (var i = at_table(e, 0u); i < at_table(e, su[batch.c_n_tables + e]); i += batch.k_table) {
        let id = su[batch.c_t_id + i];
        let now = sn_seen(robot, sf[batch.c_t_x + i], sf[batch.c_t_y + i], sf[batch.c_t_theta + i]);
        let size = vec2<f32>(params.table_length, params.table_width);
        let entry = sn_entry(now, sn_previous(e, id), period_steps);
        sn_remember(e, id, now);
        sn_push_object(e, slot, id, entry, size);
    }
}

// frame::push_links: per group, members i < j give j -> i then i -> j; then laptop -> user.
fn sn_push_links(e: u32, slot: u32) {
    for (var g = at_group(e, 0u); g < at_group(e, su[batch.c_n_groups + e]); g += batch.k_group) {
        let first = su[batch.c_g_first + g];
        let n = su[batch.c_g_count + g];
        for (var i = at_human(e, first); i < at_human(e, first + n); i += batch.k_human) {
            for (var j = i + batch.k_human; j < at_human(e, first + n); j += batch.k_human) {
                let a = su[batch.c_h_id + i];
                let b = su[batch.c_h_id + j];
                sn_push_link(e, slot, b, a);
                sn_push_link(e, slot, a, b);
            }
        }
    }
    for (var u = at_laptop_user(e, 0u); u < at_laptop_user(e, su[batch.c_n_laptop_users + e]); u += batch.k_laptop_user) {
        let human = su[batch.c_h_id + at_human(e, su[batch.c_lu_human + u])];
        let laptop = su[batch.c_l_id + at_laptop(e, su[batch.c_lu_laptop + u])];
        sn_push_link(e, slot, laptop, human);
    }
}

// frame::record: push environment e's current frame into its history; each push remembers the
// entity's pose for the next step's velocities.
// Call once per non-terminal step, after the motion.
fn sn_record(e: u32) {
    let robot = sn_robot_of(e);
    let goal = sn_axes(robot, sf[batch.c_goal_x + e], sf[batch.c_goal_y + e]);
    let slot = sn_begin_frame(e, su[batch.c_tick + e], robot, goal, sn_command(e));
    let period_steps = params.dt / SN_FRAME_PERIOD;
    sn_push_people(e, slot, robot, period_steps);
    sn_push_objects(e, slot, robot, period_steps);
    sn_push_links(e, slot);
}
