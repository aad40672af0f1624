// requires: common/regroup.wgsl
//
// Twin of src/systems/formation.rs (stage `formation`, spec 4.1 step 9, 4.5): the bookkeeping of
// formations in progress after the motion and goal re-sampling of the step. A forming crowd:
// walkers at their slots take the slot's heading; when all are there the crowd forms (standing,
// or moving to a new goal); if they stayed together for FORMATION_APPROXIMATE_AFTER steps an
// approximate standing group forms where they are. A walker at its laptop seat sits down. Same
// operations and draws in the same order as the Rust file; change both in the same commit. The
// regrouping that ends a completed formation (`regroup_canonicalize`, at the end of the Rust
// `end_crowd_formation` and `sit_down`) is called by `main` right after them, from one place
// (Mesa inlines every call, and each copy of the regrouping and obstacle rebuild costs llvmpipe
// compile time).
//
// Capacities: Rust asserts that a new group and a new laptop user fit their capacities
// (guaranteed by `Caps`: crowd formation raises the group capacity to humans / 2, laptop-use
// formation the laptop-user capacity to the laptops). Should one not fit, the GPU poisons the
// environment instead of panicking: the positions of the humans involved become NaN and the
// formation is left as it is.

// Rust `distance`.
fn distance(ax: f32, ay: f32, bx: f32, by: f32) -> f32 {
    let dx = ax - bx;
    let dy = ay - by;
    return sqrt(dx * dx + dy * dy);
}

// Rust `set_heading`: heading of human slot i, keeping its speed; the world velocity follows.
fn set_heading(i: u32, theta: f32) {
    let sc = math_sin_cos(theta);
    sf[C_H_THETA + i] = theta;
    sf[C_H_VX + i] = sf[C_H_SPEED + i] * sc.y;
    sf[C_H_VY + i] = sf[C_H_SPEED + i] * sc.x;
}

// Rust `walkers_centroid`.
fn walkers_centroid(e: u32) -> vec2<f32> {
    let hb = e * S_H_X;
    let sb = e * S_CF_HUMAN;
    let n = su[C_CF_COUNT + e];
    var x = 0.0;
    var y = 0.0;
    for (var k = sb; k < sb + n; k++) {
        let i = hb + su[C_CF_HUMAN + k];
        x += sf[C_H_X + i];
        y += sf[C_H_Y + i];
    }
    return vec2<f32>(x / f32(n), y / f32(n));
}

// Poison (see the header): the forming walkers' positions become NaN.
fn poison_crowd(e: u32) {
    let hb = e * S_H_X;
    let sb = e * S_CF_HUMAN;
    for (var k = sb; k < sb + su[C_CF_COUNT + e]; k++) {
        let i = hb + su[C_CF_HUMAN + k];
        sf[C_H_X + i] = math_nan();
        sf[C_H_Y + i] = math_nan();
    }
}

// Rust `new_group`: a new group slot (global) with the forming walkers as members, in formation
// order; NONE (and the walkers poisoned) when the group capacity is exhausted.
fn new_group(e: u32, kind: u32) -> u32 {
    if (su[C_N_GROUPS + e] >= S_G_KIND) {
        poison_crowd(e);
        return NONE;
    }
    let g = e * S_G_KIND + su[C_N_GROUPS + e];
    su[C_N_GROUPS + e] += 1u;
    su[C_G_KIND + g] = kind;
    su[C_G_DISPERSABLE + g] = 1u;
    su[C_G_SEQ + g] = regroup_next_seq(e);
    sf[C_G_VX + g] = 0.0;
    sf[C_G_VY + g] = 0.0;
    // The members are the walkers that formed the crowd, with their human goal radius.
    sf[C_G_MEMBER_GOAL_RADIUS + g] = params.human_goal_radius;
    let hb = e * S_H_X;
    let sb = e * S_CF_HUMAN;
    var member_role = ROLE_STANDING_GROUP;
    if (kind == GROUP_MOVING) {
        member_role = ROLE_MOVING_GROUP;
    }
    for (var k = sb; k < sb + su[C_CF_COUNT + e]; k++) {
        let i = hb + su[C_CF_HUMAN + k];
        su[C_H_ROLE + i] = member_role;
        su[C_H_GROUP + i] = g - e * S_G_KIND;
        su[C_H_FORMING + i] = FORMING_NONE;
        su[C_H_SEQ + i] = regroup_next_seq(e);
    }
    return g;
}

// Rust `clear_crowd_formation`.
fn clear_crowd_formation(e: u32) {
    su[C_CF_ACTIVE + e] = 0u;
    su[C_CF_COUNT + e] = 0u;
    su[C_CF_CLOSE_STEPS + e] = 0u;
    sf[C_CF_X + e] = 0.0;
    sf[C_CF_Y + e] = 0.0;
    let sb = e * S_CF_HUMAN;
    for (var k = sb; k < sb + S_CF_HUMAN; k++) {
        sf[C_CF_SLOT_X + k] = 0.0;
        sf[C_CF_SLOT_Y + k] = 0.0;
        sf[C_CF_SLOT_THETA + k] = 0.0;
        su[C_CF_HUMAN + k] = 0u;
    }
}

// Rust `clear_laptop_formation`.
fn clear_laptop_formation(e: u32) {
    su[C_LF_ACTIVE + e] = 0u;
    su[C_LF_HUMAN + e] = 0u;
    su[C_LF_LAPTOP + e] = 0u;
    sf[C_LF_SEAT_X + e] = 0.0;
    sf[C_LF_SEAT_Y + e] = 0.0;
    sf[C_LF_SEAT_THETA + e] = 0.0;
}

// Rust `end_crowd_formation`.
fn end_crowd_formation(e: u32) {
    clear_crowd_formation(e);
    // Rust: `regroup::canonicalize`, called by `main` (see the header).
}

// Rust `form_crowd`: every walker is at its slot.
fn form_crowd(e: u32, rng: ptr<function, RngStream>) {
    let n = su[C_CF_COUNT + e];
    var poses: array<vec3<f32>, PLACE_GROUP_CAP>;
    place_group_layout(rng, sf[C_CF_X + e], sf[C_CF_Y + e], n, true, &poses);
    let moving = rng_chance(rng, 0.5);
    var kind = GROUP_STANDING;
    if (moving) {
        kind = GROUP_MOVING;
    }
    let g = new_group(e, kind);
    if (g == NONE) {
        return;
    }
    let hb = e * S_H_X;
    let sb = e * S_CF_HUMAN;
    var cx = 0.0;
    var cy = 0.0;
    for (var k = 0u; k < min(n, PLACE_GROUP_CAP); k++) {
        let pose = poses[k];
        let i = hb + su[C_CF_HUMAN + sb + k];
        sf[C_H_X + i] = pose.x;
        sf[C_H_Y + i] = pose.y;
        set_heading(i, pose.z);
        cx += pose.x;
        cy += pose.y;
    }
    sf[C_G_X + g] = cx / f32(n);
    sf[C_G_Y + g] = cy / f32(n);
    if (moving) {
        let goal = goals_sample_goal(e, rng, params.group_goal_radius);
        var gx = sf[C_G_X + g];
        var gy = sf[C_G_Y + g];
        if (goal.found) {
            gx = goal.disc.x;
            gy = goal.disc.y;
        }
        sf[C_G_GOAL_X + g] = gx;
        sf[C_G_GOAL_Y + g] = gy;
        for (var k = sb; k < sb + n; k++) {
            let i = hb + su[C_CF_HUMAN + k];
            sf[C_H_GOAL_X + i] = gx;
            sf[C_H_GOAL_Y + i] = gy;
        }
    }
    end_crowd_formation(e);
}

// Rust `form_approximate_crowd`: a standing group where the walkers are, facing (cx, cy).
fn form_approximate_crowd(e: u32, rng: ptr<function, RngStream>, cx: f32, cy: f32) {
    let n = su[C_CF_COUNT + e];
    var poses: array<vec3<f32>, PLACE_GROUP_CAP>;
    place_group_layout(rng, cx, cy, n, true, &poses);
    let g = new_group(e, GROUP_STANDING);
    if (g == NONE) {
        return;
    }
    var px = 0.0;
    var py = 0.0;
    for (var k = 0u; k < min(n, PLACE_GROUP_CAP); k++) {
        px += poses[k].x;
        py += poses[k].y;
    }
    sf[C_G_X + g] = px / f32(n);
    sf[C_G_Y + g] = py / f32(n);
    let hb = e * S_H_X;
    let sb = e * S_CF_HUMAN;
    for (var k = sb; k < sb + n; k++) {
        let i = hb + su[C_CF_HUMAN + k];
        set_heading(i, math_atan2(cy - sf[C_H_Y + i], cx - sf[C_H_X + i]));
    }
    end_crowd_formation(e);
}

// Rust `crowd_progress`: 0 walking, 1 formed, 2 approximate.
fn crowd_progress(e: u32, rng: ptr<function, RngStream>) -> u32 {
    let hb = e * S_H_X;
    let sb = e * S_CF_HUMAN;
    let n = su[C_CF_COUNT + e];
    var all_arrived = true;
    for (var k = sb; k < sb + n; k++) {
        let i = hb + su[C_CF_HUMAN + k];
        if (distance(sf[C_H_X + i], sf[C_H_Y + i], sf[C_CF_SLOT_X + k], sf[C_CF_SLOT_Y + k]) < params.human_goal_radius) {
            set_heading(i, sf[C_CF_SLOT_THETA + k]);
        } else {
            all_arrived = false;
        }
    }
    if (all_arrived) {
        form_crowd(e, rng);
        return 1u;
    }
    let c = walkers_centroid(e);
    let reach = params.group_radius + params.human_radius;
    var together = true;
    for (var k = sb; k < sb + n; k++) {
        let i = hb + su[C_CF_HUMAN + k];
        if (!(distance(sf[C_H_X + i], sf[C_H_Y + i], c.x, c.y) < reach)) {
            together = false;
            break;
        }
    }
    if (together) {
        su[C_CF_CLOSE_STEPS + e] += 1u;
    } else {
        su[C_CF_CLOSE_STEPS + e] = 0u;
    }
    if (su[C_CF_CLOSE_STEPS + e] >= FORMATION_APPROXIMATE_AFTER) {
        form_approximate_crowd(e, rng, c.x, c.y);
        return 2u;
    }
    return 0u;
}

// Rust `seat_reached`.
fn seat_reached(e: u32) -> bool {
    let i = e * S_H_X + su[C_LF_HUMAN + e];
    return distance(sf[C_H_X + i], sf[C_H_Y + i], sf[C_LF_SEAT_X + e], sf[C_LF_SEAT_Y + e]) < params.human_goal_radius;
}

// Rust `sit_down`: the walker becomes a new (dispersable) laptop user at the seat.
fn sit_down(e: u32) {
    let i = e * S_H_X + su[C_LF_HUMAN + e];
    let l = e * S_L_X + su[C_LF_LAPTOP + e];
    let u_local = su[C_N_LAPTOP_USERS + e];
    if (u_local >= S_LU_HUMAN) {
        sf[C_H_X + i] = math_nan();
        sf[C_H_Y + i] = math_nan();
        return;
    }
    let u = e * S_LU_HUMAN + u_local;
    su[C_N_LAPTOP_USERS + e] += 1u;
    su[C_LU_HUMAN + u] = su[C_LF_HUMAN + e];
    su[C_LU_LAPTOP + u] = su[C_LF_LAPTOP + e];
    su[C_LU_DISPERSABLE + u] = 1u;
    su[C_LU_SEQ + u] = regroup_next_seq(e);
    su[C_L_USER + l] = u_local;
    sf[C_H_X + i] = sf[C_LF_SEAT_X + e];
    sf[C_H_Y + i] = sf[C_LF_SEAT_Y + e];
    set_heading(i, sf[C_LF_SEAT_THETA + e]);
    su[C_H_ROLE + i] = ROLE_LAPTOP_USER;
    su[C_H_LAPTOP_USER + i] = u_local;
    su[C_H_GROUP + i] = NONE;
    su[C_H_FORMING + i] = FORMING_NONE;
    su[C_H_POLICY + i] = POLICY_ORCA;
    su[C_H_SEQ + i] = regroup_next_seq(e);
    clear_laptop_formation(e);
    // Rust: `regroup::canonicalize`, called by `main` (see the header).
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= N_ENVS || su[C_STEPPING + e] == 0u) {
        return;
    }
    // The crowd, then the laptop seat, each followed by the regrouping when it completed (see
    // the header).
    for (var phase = 0u; phase < 2u; phase++) {
        var completed = false;
        if (phase == 0u) {
            if (su[C_CF_ACTIVE + e] != 0u) {
                var rng = rng_new(
                    params.seed_lo,
                    params.seed_hi,
                    e,
                    su[C_EPISODE + e],
                    rng_stream_id(STREAM_FORMATION, su[C_TICK + e]),
                );
                let progress = crowd_progress(e, &rng);
                if (progress == 1u) {
                    count_formation_event(e, EV_CROWD_FORMATION_COMPLETE);
                    completed = true;
                } else if (progress == 2u) {
                    count_formation_event(e, EV_CROWD_FORMATION_APPROXIMATE);
                    completed = true;
                }
            }
        } else if (su[C_LF_ACTIVE + e] != 0u && seat_reached(e)) {
            sit_down(e);
            count_formation_event(e, EV_LAPTOP_FORMATION_COMPLETE);
            completed = true;
        }
        if (completed) {
            regroup_canonicalize(e);
        }
    }
}

fn count_formation_event(e: u32, ev: u32) {
    outu[CO_EVENTS + e * SO_EVENTS + ev] += 1u;
}
