// requires: common/math.wgsl
//
// Twin of src/sngnn/frame.rs and src/sngnn/history/write.rs: the SNGNN input frame of one
// environment (spec 7.2) pushed into its frame history in the state's columns, and the
// robot-frame poses kept for the next step's velocities. Needs the generated SNGNN prelude
// (`backend::wgsl::sngnn_prelude`: SN_FRAMES, SN_FRAME_PEOPLE, ...). Same operations in the same
// order as the Rust, so that lavapipe computes the CPU's bits. Change both in the same commit.

// frame::ADVANCE_SCALE (9.4), ROTATION_SCALE (10.32), FRAME_PERIOD (0.2 s) as f32.
const SN_ADVANCE_SCALE: f32 = 0x1.2ccccc0p3f;
const SN_MAX_ADVANCE: f32 = 3.5;
const SN_ROTATION_SCALE: f32 = 0x1.4a3d70p3f;
const SN_MAX_ROTATION: f32 = 4.0;
const SN_FRAME_PERIOD: f32 = 0x1.99999ap-3f;

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
    return sn_robot(sf[C_ROBOT_X + e], sf[C_ROBOT_Y + e], sf[C_ROBOT_THETA + e]);
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

// ---- history columns (history/view.rs layout: slot f of env e is row e * F + f) ----

fn sn_frame_row(e: u32, slot: u32) -> u32 {
    return e * SN_FRAMES + slot;
}

// The ring slot of the frame taken `age` non-terminal steps ago (age < count).
fn sn_slot_of_age(e: u32, age: u32) -> u32 {
    return (su[C_SN_NEWEST + e] + SN_FRAMES - age) % SN_FRAMES;
}

// history::write::clear_slot: every row of ring slot `slot` zero.
fn sn_clear_slot(e: u32, slot: u32) {
    let f = sn_frame_row(e, slot);
    su[C_SF_TICK + f] = 0u;
    sf[C_SF_ROBOT_X + f] = 0.0;
    sf[C_SF_ROBOT_Y + f] = 0.0;
    sf[C_SF_ROBOT_THETA + f] = 0.0;
    sf[C_SF_GOAL_X + f] = 0.0;
    sf[C_SF_GOAL_Y + f] = 0.0;
    sf[C_SF_ADVANCE + f] = 0.0;
    sf[C_SF_LATERAL + f] = 0.0;
    sf[C_SF_ROTATION + f] = 0.0;
    su[C_SF_N_PEOPLE + f] = 0u;
    su[C_SF_N_OBJECTS + f] = 0u;
    su[C_SF_N_LINKS + f] = 0u;
    for (var i = f * SN_FRAME_PEOPLE; i < (f + 1u) * SN_FRAME_PEOPLE; i++) {
        su[C_FP_ID + i] = 0u;
        sf[C_FP_X + i] = 0.0;
        sf[C_FP_Y + i] = 0.0;
        sf[C_FP_A + i] = 0.0;
        sf[C_FP_VX + i] = 0.0;
        sf[C_FP_VY + i] = 0.0;
        sf[C_FP_VA + i] = 0.0;
    }
    for (var i = f * SN_FRAME_OBJECTS; i < (f + 1u) * SN_FRAME_OBJECTS; i++) {
        su[C_FO_ID + i] = 0u;
        sf[C_FO_X + i] = 0.0;
        sf[C_FO_Y + i] = 0.0;
        sf[C_FO_A + i] = 0.0;
        sf[C_FO_VX + i] = 0.0;
        sf[C_FO_VY + i] = 0.0;
        sf[C_FO_VA + i] = 0.0;
        sf[C_FO_SIZE_X + i] = 0.0;
        sf[C_FO_SIZE_Y + i] = 0.0;
    }
    for (var i = f * SN_FRAME_LINKS; i < (f + 1u) * SN_FRAME_LINKS; i++) {
        su[C_FL_SRC + i] = 0u;
        su[C_FL_DST + i] = 0u;
    }
}

// history::write::begin_frame: a new newest frame (the ring drops the oldest); returns its slot.
fn sn_begin_frame(e: u32, tick: u32, robot: SnRobot, goal: vec2<f32>, command: vec3<f32>) -> u32 {
    let count = su[C_SN_FRAME_COUNT + e];
    var slot = 0u;
    if (count != 0u) {
        slot = (su[C_SN_NEWEST + e] + 1u) % SN_FRAMES;
    }
    sn_clear_slot(e, slot);
    su[C_SN_NEWEST + e] = slot;
    su[C_SN_FRAME_COUNT + e] = min(count + 1u, SN_FRAMES);
    let f = sn_frame_row(e, slot);
    su[C_SF_TICK + f] = tick;
    sf[C_SF_ROBOT_X + f] = robot.x;
    sf[C_SF_ROBOT_Y + f] = robot.y;
    sf[C_SF_ROBOT_THETA + f] = robot.theta;
    sf[C_SF_GOAL_X + f] = goal.x;
    sf[C_SF_GOAL_Y + f] = goal.y;
    sf[C_SF_ADVANCE + f] = command.x;
    sf[C_SF_LATERAL + f] = command.y;
    sf[C_SF_ROTATION + f] = command.z;
    return slot;
}

// Index of entity `id`'s previous pose (ids 1..=SN_ENTITIES; the CPU panics outside, the device
// clamps so that it never writes out of the environment's rows).
fn sn_prev_index(e: u32, id: u32) -> u32 {
    return e * SN_ENTITIES + clamp(id, 1u, SN_ENTITIES) - 1u;
}

fn sn_previous(e: u32, id: u32) -> SnSeen {
    let i = sn_prev_index(e, id);
    return SnSeen(sf[C_SN_PREV_X + i], sf[C_SN_PREV_Y + i], sf[C_SN_PREV_THETA + i]);
}

fn sn_remember(e: u32, id: u32, seen: SnSeen) {
    let i = sn_prev_index(e, id);
    sf[C_SN_PREV_X + i] = seen.x;
    sf[C_SN_PREV_Y + i] = seen.y;
    sf[C_SN_PREV_THETA + i] = seen.theta;
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
    let j = su[C_SF_N_PEOPLE + f];
    if (j >= SN_FRAME_PEOPLE) {
        return;
    }
    let i = f * SN_FRAME_PEOPLE + j;
    su[C_FP_ID + i] = id;
    sf[C_FP_X + i] = v[0];
    sf[C_FP_Y + i] = v[1];
    sf[C_FP_A + i] = v[2];
    sf[C_FP_VX + i] = v[3];
    sf[C_FP_VY + i] = v[4];
    sf[C_FP_VA + i] = v[5];
    su[C_SF_N_PEOPLE + f] = j + 1u;
}

// history::write::push_object.
fn sn_push_object(e: u32, slot: u32, id: u32, v: array<f32, 6>, size: vec2<f32>) {
    let f = sn_frame_row(e, slot);
    let j = su[C_SF_N_OBJECTS + f];
    if (j >= SN_FRAME_OBJECTS) {
        return;
    }
    let i = f * SN_FRAME_OBJECTS + j;
    su[C_FO_ID + i] = id;
    sf[C_FO_X + i] = v[0];
    sf[C_FO_Y + i] = v[1];
    sf[C_FO_A + i] = v[2];
    sf[C_FO_VX + i] = v[3];
    sf[C_FO_VY + i] = v[4];
    sf[C_FO_VA + i] = v[5];
    sf[C_FO_SIZE_X + i] = size.x;
    sf[C_FO_SIZE_Y + i] = size.y;
    su[C_SF_N_OBJECTS + f] = j + 1u;
}

// history::write::push_link.
fn sn_push_link(e: u32, slot: u32, src: u32, dst: u32) {
    let f = sn_frame_row(e, slot);
    let j = su[C_SF_N_LINKS + f];
    if (j >= SN_FRAME_LINKS) {
        return;
    }
    let i = f * SN_FRAME_LINKS + j;
    su[C_FL_SRC + i] = src;
    su[C_FL_DST + i] = dst;
    su[C_SF_N_LINKS + f] = j + 1u;
}

// frame::command: advance, lateral advance, rotation in SNGNN units.
fn sn_command(e: u32) -> vec3<f32> {
    var lateral = 0.0;
    if (params.holonomic != 0u) {
        lateral = min(SN_ADVANCE_SCALE * sf[C_ROBOT_VY + e], SN_MAX_ADVANCE);
    }
    let advance = min(SN_ADVANCE_SCALE * sf[C_ROBOT_VX + e], SN_MAX_ADVANCE);
    let rotation = clamp(SN_ROTATION_SCALE * sf[C_ROBOT_W + e], -SN_MAX_ROTATION, SN_MAX_ROTATION);
    return vec3<f32>(advance, lateral, rotation);
}

// frame::push_people: every human in slot order, remembering each pose.
fn sn_push_people(e: u32, slot: u32, robot: SnRobot, period_steps: f32) {
    let hb = e * S_H_X;
    for (var i = hb; i < hb + su[C_N_HUMANS + e]; i++) {
        let id = su[C_H_ID + i];
        let now = sn_seen(robot, sf[C_H_X + i], sf[C_H_Y + i], sf[C_H_THETA + i]);
        let entry = sn_entry(now, sn_previous(e, id), period_steps);
        sn_remember(e, id, now);
        sn_push_person(e, slot, id, entry);
    }
}

// frame::push_objects: laptops, plants (2r x 2r), tables.
fn sn_push_objects(e: u32, slot: u32, robot: SnRobot, period_steps: f32) {
    let lb = e * S_L_X;
    for (var i = lb; i < lb + su[C_N_LAPTOPS + e]; i++) {
        let id = su[C_L_ID + i];
        let now = sn_seen(robot, sf[C_L_X + i], sf[C_L_Y + i], sf[C_L_THETA + i]);
        let size = vec2<f32>(params.laptop_length, params.laptop_width);
        let entry = sn_entry(now, sn_previous(e, id), period_steps);
        sn_remember(e, id, now);
        sn_push_object(e, slot, id, entry, size);
    }
    let pb = e * S_P_X;
    let diameter = 2.0 * params.plant_radius;
    for (var i = pb; i < pb + su[C_N_PLANTS + e]; i++) {
        let id = su[C_P_ID + i];
        let now = sn_seen(robot, sf[C_P_X + i], sf[C_P_Y + i], 0.0);
        let size = vec2<f32>(diameter, diameter);
        let entry = sn_entry(now, sn_previous(e, id), period_steps);
        sn_remember(e, id, now);
        sn_push_object(e, slot, id, entry, size);
    }
    let tb = e * S_T_X;
    for (var i = tb; i < tb + su[C_N_TABLES + e]; i++) {
        let id = su[C_T_ID + i];
        let now = sn_seen(robot, sf[C_T_X + i], sf[C_T_Y + i], sf[C_T_THETA + i]);
        let size = vec2<f32>(params.table_length, params.table_width);
        let entry = sn_entry(now, sn_previous(e, id), period_steps);
        sn_remember(e, id, now);
        sn_push_object(e, slot, id, entry, size);
    }
}

// frame::push_links: per group, members i < j give j -> i then i -> j; then laptop -> user.
fn sn_push_links(e: u32, slot: u32) {
    let hb = e * S_H_X;
    let gb = e * S_G_FIRST;
    for (var g = gb; g < gb + su[C_N_GROUPS + e]; g++) {
        let first = hb + su[C_G_FIRST + g];
        let n = su[C_G_COUNT + g];
        for (var i = first; i < first + n; i++) {
            for (var j = i + 1u; j < first + n; j++) {
                let a = su[C_H_ID + i];
                let b = su[C_H_ID + j];
                sn_push_link(e, slot, b, a);
                sn_push_link(e, slot, a, b);
            }
        }
    }
    let ub = e * S_LU_HUMAN;
    let lb = e * S_L_X;
    for (var u = ub; u < ub + su[C_N_LAPTOP_USERS + e]; u++) {
        let human = su[C_H_ID + hb + su[C_LU_HUMAN + u]];
        let laptop = su[C_L_ID + lb + su[C_LU_LAPTOP + u]];
        sn_push_link(e, slot, laptop, human);
    }
}

// frame::record: push environment e's current frame into its history; each push remembers the
// entity's pose for the next step's velocities.
// Call once per non-terminal step, after the motion.
fn sn_record(e: u32) {
    let robot = sn_robot_of(e);
    let goal = sn_axes(robot, sf[C_GOAL_X + e], sf[C_GOAL_Y + e]);
    let slot = sn_begin_frame(e, su[C_TICK + e], robot, goal, sn_command(e));
    let period_steps = params.dt / SN_FRAME_PERIOD;
    sn_push_people(e, slot, robot, period_steps);
    sn_push_objects(e, slot, robot, period_steps);
    sn_push_links(e, slot);
}
